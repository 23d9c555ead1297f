// `implicit da`'s experiment: the confidence interval over seeds from the per-seed rmse.a, the
// Student-t quantiles it uses, and the benchmark settings' sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "experiments/da.hpp"
#include "experiments/run_statistics.hpp"

namespace implicit::experiments {
namespace {

TEST(DaExperiment, ConfidenceIntervalIsTheStudentIntervalOfThePerSeedScores) {
  DaSettings s;
  s.method = "etkf";
  s.members = 6;
  s.inflation = 1.05;
  s.seeds = 3;
  s.cycles = 40;  // 10 time units: 24 cycles after the burn-in of 4
  RunContext ctx;
  ctx.seed = 4;
  ctx.quiet = true;
  const auto r = run_da(s, ctx);
  std::vector<double> v;
  for (const auto& run : r["runs"]) v.push_back(run["rmse_a"].get<double>());
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(r["runs"][2]["seed"].get<int>(), 6);
  const double half = 4.303 * sd_of(v) / std::sqrt(3.0);  // t_{0.975, 2} = 4.303
  EXPECT_DOUBLE_EQ(r["rmse_a"]["mean"].get<double>(), mean_of(v));
  EXPECT_NEAR(r["rmse_a"]["ci95"][0].get<double>(), mean_of(v) - half, 1e-12);
  EXPECT_NEAR(r["rmse_a"]["ci95"][1].get<double>(), mean_of(v) + half, 1e-12);
  EXPECT_EQ(r["setting"], "sakov2012");
  EXPECT_EQ(r["mean_ess"].get<double>(), 6.0);
}

TEST(DaExperiment, StudentQuantilesMatchTheTables) {
  EXPECT_DOUBLE_EQ(student_t975(1), 12.706);
  EXPECT_DOUBLE_EQ(student_t975(9), 2.262);
  // Beyond the table, the Cornish-Fisher expansion against tabulated values (3 decimals).
  EXPECT_NEAR(student_t975(40), 2.021, 1e-3);
  EXPECT_NEAR(student_t975(120), 1.980, 1e-3);
}

TEST(DaExperiment, Lorenz96SettingObservesEveryOtherComponent) {
  DaSettings s;
  s.model = "lorenz96";
  s.dim = 10;
  const auto d = da_setup(s, 1);
  EXPECT_EQ(d.problem.obs_dim(), 5);
  EXPECT_EQ(d.problem.H(4, 8), 1.0);
  EXPECT_EQ(d.problem.R(0, 0), 2.25);
  EXPECT_EQ(d.twin.cycles, 1280);
  EXPECT_EQ(d.setting, "bocquet2010");
  s.dim = 11;  // odd n: indices 0, 2, ..., 10
  EXPECT_EQ(da_setup(s, 1).problem.obs_dim(), 6);
  // Another n or F is another benchmark, never matched with the 10-variable DAPPER rows.
  s.dim = 40;
  EXPECT_EQ(da_setup(s, 1).setting, "bocquet2010-n40");
  s.forcing = 10.0;
  EXPECT_EQ(da_setup(s, 1).setting, "bocquet2010-n40-F10");
  s.dim = 10;
  EXPECT_EQ(da_setup(s, 1).setting, "bocquet2010-F10");
}

}  // namespace
}  // namespace implicit::experiments
