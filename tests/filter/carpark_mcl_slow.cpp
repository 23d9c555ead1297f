// Implicit and standard MCL on the real Car Park data (config A, the paper's P = 0.5) against the
// independent reference of spec §3.9. These are many-seed runs (about a minute in Release), so
// they live in the slow program.
//
// Single batches of 20 runs are noisy in config A: the "lost" count (runs whose maximum position
// error exceeds 5 m) is a binomial count whose typical runs already reach 3-4 m at the end of the
// 3.9 s stretch without detections (108-112 s), so a batch of 20 can show 10 lost runs at M = 300
// when the rate over hundreds of seeds is about 9 % (the reference: 2 of 20). The checks below use
// the median err% and rates over many seeds, with tolerances derived from their standard errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "implicit/filter/localization.hpp"
#include "implicit/robot/carpark.hpp"

namespace implicit::filter {
namespace {

struct Batch {
  std::vector<double> error_percent;
  int lost = 0;
  double ess_fraction = 0.0;  ///< mean over runs
};

const LocalizationProblem& carpark_problem(const robot::UteModel& model) {
  static const LocalizationProblem p = make_problem(
      robot::carpark_to_log(robot::load_carpark(robot::default_carpark_dir()), model), model.dt());
  return p;
}

template <typename Proposal>
Batch run_batch(const Proposal& proposal, std::size_t particles, int runs, std::uint64_t first) {
  const robot::UteModel model;  // config A: P = diag(0.5, 0.5)
  const robot::RangeBearingSensor sensor;
  const LocalizationProblem& problem = carpark_problem(model);
  Batch b;
  for (int r = 0; r < runs; ++r) {
    FilterOptions options;
    options.particles = particles;
    options.seed = first + static_cast<std::uint64_t>(r);
    const LocalizationRun run = run_localization(problem, model, sensor, proposal, options);
    const LocalizationMetrics m = localization_metrics(run, problem.truth, particles);
    b.error_percent.push_back(m.error_percent);
    b.lost += m.max_error > 5.0 ? 1 : 0;
    b.ess_fraction += m.ess_fraction / runs;
  }
  return b;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

TEST(CarParkMcl, ImplicitAtThousandParticlesMatchesReference) {
  // Reference (spec §3.9, M = 1000, 20 seeds): 3.71 +- 0.47 %, no lost run. Our median over 10
  // seeds has SE ~ 1.25 * 0.47 / sqrt(10) = 0.19; the reference mean SE 0.47 / sqrt(20) = 0.11;
  // combined 0.21, and 4.5 SE = 0.95.
  const Batch b = run_batch(ImplicitProposal{}, 1000, 10, 7000);
  const double med = median(b.error_percent);
  RecordProperty("median_error_percent", std::to_string(med));
  EXPECT_NEAR(med, 3.71, 0.95);
  // ESS/M stays near 0.39 (reference); per-run ESS/M varies by ~0.01, so 0.05 is > 4.5 SE.
  EXPECT_NEAR(b.ess_fraction, 0.39, 0.05);
}

TEST(CarParkMcl, ImplicitLosesFewerRunsThanStandardAtEqualParticles) {
  // M = 300. Reference: implicit 4.18 +- 1.06 (median 3.97), 2 of 20 lost; standard median 5.69,
  // 10 of 20 lost. Over hundreds of our seeds: implicit ~9 % lost, standard ~59 %.
  constexpr int kRuns = 40;
  const Batch imp = run_batch(ImplicitProposal{}, 300, kRuns, 9000);
  const Batch std_ = run_batch(BootstrapProposal{}, 300, kRuns, 9000);
  const double med = median(imp.error_percent);
  RecordProperty("implicit_median_error_percent", std::to_string(med));
  RecordProperty("implicit_lost", imp.lost);
  RecordProperty("standard_lost", std_.lost);
  // Median err% of the non-lost bulk: SE ~ 1.25 * 1.06 / sqrt(40) = 0.21 here and 0.30 for the
  // reference's 20 runs; combined 0.37, 4.5 SE = 1.65.
  EXPECT_NEAR(med, 3.97, 1.65);
  // Lost fractions (binomial): difference ~0.5 with SE sqrt(.09 .91 / 40 + .59 .41 / 40) = 0.088;
  // requiring a difference of at least 0.15 leaves 4 SE of margin.
  EXPECT_LE(imp.lost + static_cast<int>(0.15 * kRuns), std_.lost);
  // The implicit lost rate itself: 0.09 + 4.5 sqrt(.09 .91 / 40) = 0.29, i.e. at most 11 of 40.
  EXPECT_LE(imp.lost, 11);
  EXPECT_LT(med, median(std_.error_percent));
}

}  // namespace
}  // namespace implicit::filter
