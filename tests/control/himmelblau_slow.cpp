// Himmelblau via stochastic control: the 400-run expected outcome of spec §2.6 and a large-run
// check of the closed-form reference (himmelblau_bridge_reference).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "implicit/control/himmelblau.hpp"
#include "implicit/core/parallel.hpp"

using namespace implicit::control;
using implicit::Vec;

namespace {
struct Summary {
  double cost = 0.0, cost_se = 0.0, adjusted = 0.0, adjusted_se = 0.0, f19 = 0.0, f19_se = 0.0;
  double max_laplace_gap = 0.0;
  int below_10 = 0;
};

double mean(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m += x / static_cast<double>(v.size());
  return m;
}
double standard_error(const std::vector<double>& v) {
  const double m = mean(v), n = static_cast<double>(v.size());
  double q = 0.0;
  for (double x : v) q += (x - m) * (x - m);
  return std::sqrt(q / (n - 1.0) / n);
}

Summary simulate(const HimmelblauProblem& pb, int runs, std::uint64_t seed) {
  const auto ref = himmelblau_bridge_reference(pb);
  std::vector<HimmelblauRun> out(static_cast<std::size_t>(runs));
  implicit::parallel_for(
      out.size(), [&](std::size_t r) { out[r] = simulate_himmelblau_run(pb, 50, seed, r); }, 1);
  std::vector<double> cost, adjusted, f19;
  Summary s;
  for (const auto& r : out) {
    cost.push_back(r.cost);
    adjusted.push_back(last_step_adjusted_cost(pb, r, ref));
    f19.push_back(himmelblau(r.x[r.x.size() - 2]));
    s.max_laplace_gap = std::max(s.max_laplace_gap, r.max_laplace_gap);
    s.below_10 += r.final_f < 10.0 ? 1 : 0;
  }
  s.cost = mean(cost);
  s.cost_se = standard_error(cost);
  s.adjusted = mean(adjusted);
  s.adjusted_se = standard_error(adjusted);
  s.f19 = mean(f19);
  s.f19_se = standard_error(f19);
  return s;
}
}  // namespace

TEST(HimmelblauSlow, FourHundredRunsAgainstClosedForm) {
  // The spec's protocol (400 runs, M = 50) for several seeds. Raw means within 4.5 SE of the
  // closed form; the last-step-adjusted cost (control variate, bias ~1e-5) within 4.5 of its SE.
  // Seed 2 is the unlucky one: the sample variance of its last noise step W_19 (first
  // coordinate) over the 400 runs is 1.27, 3.8 of its sd sqrt(2/399) above 1 (1 seed in 2000
  // does that), which lifts its raw mean cost to 1.21 (2.9 SE); its adjusted cost agrees with
  // the closed form like the others. That was the whole "disagreement" with the spec.
  const HimmelblauProblem pb;
  const auto ref = himmelblau_bridge_reference(pb);
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto s = simulate(pb, 400, seed);
    EXPECT_EQ(s.below_10, 400) << "seed " << seed;
    EXPECT_LT(s.max_laplace_gap, 2e-6) << "seed " << seed;
    EXPECT_NEAR(s.cost, ref.cost(), 4.5 * s.cost_se) << "seed " << seed;
    EXPECT_NEAR(s.f19, ref.f_before_last_step, 4.5 * s.f19_se) << "seed " << seed;
    EXPECT_NEAR(s.adjusted, ref.cost(), 4.5 * s.adjusted_se + 1e-5) << "seed " << seed;
  }
  // The spec's own 400-run figures are Monte Carlo estimates of the same expectations: both lie
  // within 1.1 of their standard errors (0.054 = sd 1.074 / 20; 0.137 = sd 2.737 / 20).
  EXPECT_LT(std::abs(0.998 - ref.cost()), 1.1 * ref.final_f_sd / 20.0);
  EXPECT_LT(std::abs(2.70 - ref.f_before_last_step), 1.1 * ref.f_before_last_step_sd / 20.0);
}

TEST(HimmelblauSlow, ManyRunsResolveTheReference) {
  // 4000 runs: SE 0.017 for the cost and 0.043 for f(x_19); the adjusted cost pins the control
  // part (0.00241) to about 2e-5.
  const HimmelblauProblem pb;
  const auto ref = himmelblau_bridge_reference(pb);
  const auto s = simulate(pb, 4000, 11);
  EXPECT_NEAR(s.cost, ref.cost(), 4.5 * s.cost_se);
  EXPECT_NEAR(s.f19, ref.f_before_last_step, 4.5 * s.f19_se);
  EXPECT_NEAR(s.adjusted, ref.cost(), 4.5 * s.adjusted_se + 1e-5);
  EXPECT_LT(s.max_laplace_gap, 2e-6);
}
