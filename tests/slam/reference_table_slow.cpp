// The SLAM estimators against the independent reference table of spec §3.10 (M = 100, known
// association, paper-like truth), over many more data sets than the table's 50.
//
// Why many: the table's map shape is a 50-run mean whose run-to-run spread (sd 0.05-0.07 m, mostly
// the filter's own randomness) gives it a standard error of about 0.009 m, so a single block of 50
// data sets can sit 0.02 m from the population mean (FastSLAM 1.0 on our data sets 1-50: 0.200 m,
// 51-100: 0.230 m, 701-750: 0.171 m; population 0.189 m). The check below is therefore the
// two-sample one: |ours - table| <= 4.5 sqrt(SE_ours^2 + SE_table^2), with SE_table = sd / sqrt(50)
// from our own spread (a correct implementation has the same spread as the reference). ESS/M and
// the resampling count hardly vary between runs; they must be within the spec's +-3 %.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "core/stat_helpers.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"
#include "slam/test_data.hpp"

namespace implicit::slam {
namespace {

struct Row {
  SlamMethod method;
  double map_shape_m, ess_fraction, resamplings;  // spec §3.10, M = 100, 50 data sets
  bool particles = true;                          // false: EKF-SLAM (no ESS, no resampling)
};

using implicit::testing::summarise_runs;

SlamOptions options_m100(SlamMethod method, std::uint64_t seed) {
  SlamOptions opt;
  opt.method = method;
  opt.particles = 100;
  opt.seed = seed;
  return opt;
}

void check_against_table(const Row& row, std::size_t datasets) {
  const SlamScenario sc = load_carpark_scenario(repository_data_dir());
  const SyntheticConfig paper_like;
  std::vector<double> shape(datasets), ess(datasets), resamplings(datasets);
  // Data set i and its filter use seed i + 1, as `implicit slam --datasets N --seed 1` does.
  parallel_for(
      datasets,
      [&](std::size_t i) {
        const std::uint64_t seed = i + 1;
        const SlamDataset data = generate_synthetic(sc, paper_like, seed);
        const SlamRun run = run_filter(data, options_m100(row.method, seed));
        shape[i] = evaluate(data, run).map_shape_m;
        ess[i] = run.stats.mean_ess_fraction();
        resamplings[i] = static_cast<double>(run.stats.resamplings);
      },
      1);
  const auto s = summarise_runs(shape);
  const double se = std::sqrt(s.se * s.se + s.sd * s.sd / 50.0);
  std::string what = fmt::format(
      "{} over {} data sets: map shape {:.4f} m (sd {:.4f}), table {:.3f}, |difference| {:.4f} m, "
      "4.5 combined SE {:.4f} m",
      to_string(row.method), datasets, s.mean, s.sd, row.map_shape_m,
      std::abs(s.mean - row.map_shape_m), 4.5 * se);
  if (row.particles) {
    const auto e = summarise_runs(ess), r = summarise_runs(resamplings);
    what += fmt::format("; ESS/M {:.4f}, table {:.3f}; resamplings {:.1f}, table {:.0f}", e.mean,
                        row.ess_fraction, r.mean, row.resamplings);
    EXPECT_LE(std::abs(e.mean - row.ess_fraction), 0.03 * row.ess_fraction) << what;
    EXPECT_LE(std::abs(r.mean - row.resamplings), 0.03 * row.resamplings) << what;
  }
  EXPECT_LE(std::abs(s.mean - row.map_shape_m), 4.5 * se) << what;
  std::printf("%s\n", what.c_str());
}

// EKF-SLAM is deterministic given the data: its spread is the data sets' alone.
TEST(SlamReferenceTableSlow, Ekf) {
  check_against_table({SlamMethod::kEkf, 0.040, 0.0, 0.0, false}, 400);
}
TEST(SlamReferenceTableSlow, FastSlam1) {
  check_against_table({SlamMethod::kFastSlam1, 0.176, 0.377, 4084}, 400);
}
// A sharper check of FastSLAM 1.0 than the 50-run table allows: an independent numpy
// implementation of spec §3.5 (python/crosscheck/fastslam1_numpy.py, its own model, Jacobians,
// alignment and random numbers) gives a mean map shape of 0.1893 m, SE 0.0015 m, over 2000 runs on
// the ten reference data sets paper_le1_seed1..10 (200 runs each, a distinct filter seed per run).
// Ours on the same data sets, with a filter seed of its own per run (runs that share a seed share
// the particle noise, and all data sets share the truth path, so their errors would correlate).
TEST(SlamReferenceTableSlow, FastSlam1AgreesWithIndependentImplementation) {
  constexpr double kNumpyMean = 0.1893, kNumpySe = 0.0015;
  const SlamScenario sc = load_carpark_scenario(repository_data_dir());
  constexpr std::size_t kSets = 10, kRuns = 30;
  std::vector<SlamDataset> data;
  for (std::size_t k = 1; k <= kSets; ++k)
    data.push_back(read_reference_csv(
        repository_data_dir() / "slam-synthetic" / fmt::format("paper_le1_seed{}.csv.gz", k),
        sc.landmarks));
  std::vector<double> shape(kSets * kRuns);
  parallel_for(
      shape.size(),
      [&](std::size_t i) {
        const SlamDataset& d = data[i / kRuns];
        const SlamRun run = run_filter(d, options_m100(SlamMethod::kFastSlam1, 7000 + i));
        shape[i] = evaluate(d, run).map_shape_m;
      },
      1);
  const auto s = summarise_runs(shape);
  const double se = std::sqrt(s.se * s.se + kNumpySe * kNumpySe);
  const std::string what = fmt::format(
      "fastslam1 on the reference data sets, {} runs: map shape {:.4f} m (sd {:.4f}); numpy "
      "{:.4f} +- {:.4f} m; |difference| {:.4f}, 4.5 combined SE {:.4f}",
      shape.size(), s.mean, s.sd, kNumpyMean, kNumpySe, std::abs(s.mean - kNumpyMean), 4.5 * se);
  EXPECT_LE(std::abs(s.mean - kNumpyMean), 4.5 * se) << what;
  std::printf("%s\n", what.c_str());
}
TEST(SlamReferenceTableSlow, FastSlam2) {
  check_against_table({SlamMethod::kFastSlam2, 0.135, 0.657, 967}, 400);
}
TEST(SlamReferenceTableSlow, ImplicitPaper) {
  check_against_table({SlamMethod::kImplicit, 0.368, 0.629, 1281}, 400);
}
TEST(SlamReferenceTableSlow, ImplicitRaoBlackwellised) {
  check_against_table({SlamMethod::kImplicitRb, 0.132, 0.657, 970}, 400);
}

}  // namespace
}  // namespace implicit::slam
