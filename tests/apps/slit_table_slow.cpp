// Full Table 2 (spec §2.4.7): 500 closed-loop runs at M = 10, 50, 100, 500 for the paper's
// estimator and the corrected one. Tolerance: 4.5 standard errors of our 500-run mean
// (sd / sqrt(500)); at M = 10 the distributions are heavy-tailed, so only medians are checked.
#include <gtest/gtest.h>

#include <cmath>

#include "experiments/slit_table.hpp"
#include "implicit/control/double_slit.hpp"

using namespace implicit::control;
using namespace implicit::experiments;

namespace {
SlitTable table(int M, SlitEstimator e) {
  SlitTableOptions o;
  o.samples = M;
  o.runs = 500;
  o.estimator = e;
  o.seed = 7;
  return run_slit_table(DoubleSlit{}, o);
}
double se(double sd) { return sd / std::sqrt(500.0); }
}  // namespace

TEST(SlitTable2Full, CorrectedMode) {
  const int ms[] = {50, 100, 500};
  const double ex[] = {0.0029, 0.0019, 0.0008};
  const double eu[] = {0.0243, 0.0167, 0.0073};
  double previous = 1.0;
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(testing::Message() << "M = " << ms[i]);
    const auto t = table(ms[i], SlitEstimator::kFrozenWall);
    EXPECT_NEAR(t.error_x_mean, ex[i], 4.5 * se(t.error_x_std));
    EXPECT_NEAR(t.error_u_mean, eu[i], 4.5 * se(t.error_u_std));
    EXPECT_LT(t.error_u_mean, previous);
    previous = t.error_u_mean;
  }
  // ~ M^-1/2 from M = 50 to 500: the ratio sqrt(10) = 3.16, allowing for the O(1/M) bias.
  const auto t50 = table(50, SlitEstimator::kFrozenWall);
  const auto t500 = table(500, SlitEstimator::kFrozenWall);
  EXPECT_GT(t50.error_u_mean / t500.error_u_mean, 2.5);
  EXPECT_LT(t500.error_u_mean, 0.01);
  const auto t10 = table(10, SlitEstimator::kFrozenWall);
  EXPECT_NEAR(t10.error_u_median, 0.077, 0.015);
}

TEST(SlitTable2Full, PaperMode) {
  const int ms[] = {50, 100, 500};
  const double ex[] = {0.0261, 0.0256, 0.0249};
  const double eu[] = {0.0496, 0.0494, 0.0470};
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(testing::Message() << "M = " << ms[i]);
    const auto t = table(ms[i], SlitEstimator::kPaper);
    EXPECT_NEAR(t.error_x_mean, ex[i], 4.5 * se(t.error_x_std));
    EXPECT_NEAR(t.error_u_mean, eu[i], 4.5 * se(t.error_u_std));
    EXPECT_GT(t.crash_fraction, t.exact_crash_fraction + 0.1);
  }
  const auto t10 = table(10, SlitEstimator::kPaper);
  EXPECT_NEAR(t10.error_u_median, 0.039, 0.006);
  EXPECT_NEAR(t10.error_x_median, 0.025, 0.003);
}

TEST(SlitTable2Full, PaperModeCrashFraction) {
  // Why P crashes about half the time: it aims at the dominant slit's edge, and on the last
  // step before the wall u_P = (e - x) / dt exactly
  // (DoubleSlitControl.PaperEstimatorAimsAtTheEdge), so x(t1) = e + sqrt(sigma dt) W_49 misses the
  // slit whenever W_49 points outwards: probability 1/2. Steps where the constraint is inactive and
  // the FD spikes of the pass count (which push into the slit) lower it a little, more so for
  // larger M.
  //
  // Reference: an independent numpy implementation of spec §2.4.4-2.4.6 (estimator P with
  // common noise, exact control from log_ndtr) gave 0.453 (10 000 runs) at M = 10 and 0.442
  // (2 000 runs) at M = 50; exact-control crash fraction 0.234. Tolerance: 4.5 times the
  // combined binomial SE sqrt(p(1-p)/R) of the two estimates.
  //
  // The spec's "about 0.49" (pass 0.51) is a 500-run estimate (SE 0.022); with 20 000 runs the
  // crash fraction at M = 50 is 0.447 +- 0.0035, more than 4.5 SE below 0.49. A 500-run table
  // gives anything from about 0.40 to 0.49 depending on the seed.
  const int runs = 20000;
  auto binomial_se = [](double p, double n) { return std::sqrt(p * (1.0 - p) / n); };
  const double ms[] = {10, 50};
  const double reference[] = {0.453, 0.442};
  const double reference_runs[] = {10000, 2000};
  for (int i = 0; i < 2; ++i) {
    SCOPED_TRACE(testing::Message() << "M = " << ms[i]);
    SlitTableOptions o;
    o.samples = static_cast<int>(ms[i]);
    o.runs = runs;
    o.estimator = SlitEstimator::kPaper;
    o.seed = 11;
    const auto t = run_slit_table(DoubleSlit{}, o);
    const double se = binomial_se(t.crash_fraction, runs);
    EXPECT_NEAR(t.crash_fraction, reference[i],
                4.5 * std::hypot(se, binomial_se(reference[i], reference_runs[i])));
    EXPECT_NEAR(t.exact_crash_fraction, 0.234,
                4.5 * std::hypot(binomial_se(0.234, runs), binomial_se(0.234, 10000)));
    EXPECT_LT(t.crash_fraction, 0.5 - 4.5 * se);
    if (ms[i] == 50) {
      EXPECT_LT(t.crash_fraction, 0.49 - 4.5 * se);
    }
  }
}
