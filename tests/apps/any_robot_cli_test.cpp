// `implicit simulate` writes a log for any shipped robot; `mcl` (and `slam`) read it back with the
// matching --model and refuse the other one with exit code 1 and the reason.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>

#include "apps/cli_runner.hpp"

namespace implicit::test {
namespace {

TEST(AnyRobotCli, SimulatedUnicycleLogRunsWithItsModelAndIsRefusedByTheOther) {
  TempDir dir("any_robot");
  const std::string log = (dir.path() / "u.log.gz").string();
  const auto sim = run_cli("simulate --model unicycle --seed 3 --steps 600 --out '" + log + "'");
  ASSERT_EQ(sim.code, 0) << sim.err;

  const auto mcl =
      run_cli("mcl --model unicycle --data '" + log + "' --method implicit -M 50 --runs 1 --json");
  ASSERT_EQ(mcl.code, 0) << mcl.err;
  const auto j = nlohmann::json::parse(mcl.out);
  EXPECT_EQ(j["model"], "unicycle");
  EXPECT_LT(j["rmse_m"].get<double>(), 0.5);  // see filter/any_robot_test.cpp for the bound
  EXPECT_GT(j["dead_reckoning_error_percent"].get<double>(), j["error_percent_mean"].get<double>());

  // Without --model the log's declaration is used.
  const auto implied = run_cli("mcl --data '" + log + "' -M 20 --runs 1 --json");
  ASSERT_EQ(implied.code, 0) << implied.err;
  EXPECT_EQ(nlohmann::json::parse(implied.out)["model"], "unicycle");

  const auto wrong = run_cli("mcl --model ute --data '" + log + "'");
  EXPECT_EQ(wrong.code, 1);
  EXPECT_NE(wrong.err.find("declares vehicle 'unicycle'"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("--model unicycle"), std::string::npos) << wrong.err;
}

// slam on a unicycle log: --control-noise (the Ute's P) is refused instead of ignored, and the
// JSON gives the unicycle noise the filter used, so the run can be repeated from it.
TEST(AnyRobotCli, SlamOnAUnicycleRefusesTheUteNoiseAndReportsItsOwn) {
  TempDir dir("any_robot_slam");
  const std::string log = (dir.path() / "u.log.gz").string();
  ASSERT_EQ(run_cli("simulate --model unicycle --seed 3 --steps 300 --out '" + log + "'").code, 0);
  const std::string slam = "slam --method ekf --datasets 1 --json --data '" + log + "'";
  const auto refused = run_cli(slam + " --control-noise 0.3");
  EXPECT_EQ(refused.code, 1) << refused.err;
  EXPECT_NE(refused.err.find("--control-noise 0.3"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--control-sd U1 U2 (sd of u1 = v [m/s], u2 = omega [rad/s])"),
            std::string::npos)
      << refused.err;
  const auto r = run_cli(slam + " --control-sd 0.2 0.07");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["control_noise"].is_null());
  EXPECT_EQ(j["control_sd"], nlohmann::json::array({0.2, 0.07}));
  EXPECT_EQ(j["state_sd"].size(), 3u);
}

TEST(AnyRobotCli, TheCarParkIsAUteAndRefusesTheUnicycle) {
  const auto r = run_cli("mcl --model unicycle -M 10 --runs 1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("declares vehicle 'ute'"), std::string::npos) << r.err;
}

// A log whose scans come at four times the control rate: one scan per control is used, the rest
// are counted and said (stderr and JSON), never dropped silently.
TEST(AnyRobotCli, ScansTheScheduleLeavesOutAreCountedAndSaid) {
  TempDir dir("skipped_scans");
  const auto log = dir.path() / "fast_scans.log";
  {
    std::ofstream out(log);
    out << "vehicle unicycle dt=0.1\nlandmark 1 5 0\nlandmark 2 5 3\n"
        << "initial 0 0 0 0 0.1 0.1 0.01\n";
    for (int k = 1; k <= 20; ++k) out << "control " << 0.1 * k << " 1 0\n";
    // Two scans per control, 0.01 s and 0.02 s after it: the second finds its control taken.
    for (int k = 1; k <= 19; ++k)
      for (double offset : {0.01, 0.02})
        out << "scan " << 0.1 * k + offset << " 2\nobs 5 1.5708 1\nobs 5.8 2.1 2\n";
  }
  for (const std::string command : {"mcl -M 20", "slam -M 20 --datasets 1"}) {
    const auto r = run_cli(command + " --data '" + log.string() + "' --allow-empty --json");
    ASSERT_EQ(r.code, 0) << command << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["detections_skipped"], 38) << command;
    EXPECT_NE(r.err.find("warning: 38 detections in 19 scans"), std::string::npos)
        << command << "\n"
        << r.err;
    EXPECT_NE(r.err.find("within 0.05 s"), std::string::npos) << r.err;
  }
}

TEST(AnyRobotCli, SimulateNeedsAnOutputFile) {
  const auto r = run_cli("simulate --model unicycle");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace implicit::test
