// --trajectory and --truth-trajectory of `implicit mcl` (landmarks and laser) and `implicit slam`:
// the two TUM files, scored by `implicit eval --align none`, give back the run's own position and
// heading RMSE (Car Park: row by row against the run's CSV, and the heading RMSE). That ties the
// files to the run: a wrong time, a shifted step or a dropped pose would change the score.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

constexpr double kTrajectoryFilesPi = 3.14159265358979323846;

struct TrajectoryFilesScore {
  double translation_rmse, rotation_rmse_rad;
  int count;
};

// APE without alignment of `est` against `ref`.
TrajectoryFilesScore trajectory_files_ape(const std::string& ref, const std::string& est) {
  const auto r = run_cli("eval --align none --json --ref " + ref + " --est " + est);
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) return {NAN, NAN, 0};
  const auto j = nlohmann::json::parse(r.out)["ape"];
  return {j["translation_m"]["rmse"].get<double>(),
          j["rotation_deg"]["rmse"].get<double>() * kTrajectoryFilesPi / 180.0,
          j["translation_m"]["count"].get<int>()};
}

// The rows of a TUM file as (t, x, y, heading).
std::vector<std::array<double, 4>> trajectory_files_read_tum(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::array<double, 4>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double t, x, y, z, qx, qy, qz, qw;
    fields >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    rows.push_back({t, x, y, 2.0 * std::atan2(qz, qw)});
  }
  return rows;
}

double trajectory_files_angle_gap(double a, double b) {
  return std::abs(std::remainder(a - b, 2.0 * kTrajectoryFilesPi));
}

// Car Park: the truth file has the steps whose truth has a heading (the GPS track's direction
// where the vehicle moves), so the translation scores of eval and the run count different steps;
// the files are checked row by row against the run's own CSV (one run: it is the median run), and
// the heading scores agree.
TEST(TrajectoryFiles, LandmarkMclFilesAreTheRunsStepsAndScoreItsHeading) {
  TempDir dir("trajectory_files_mcl");
  const std::string est = (dir.path() / "est.tum").string(),
                    ref = (dir.path() / "truth.tum").string();
  const auto r =
      run_cli("mcl --method implicit -M 20 --runs 1 --quiet --json --out " + dir.path().string() +
              " --trajectory " + est + " --truth-trajectory " + ref);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto est_rows = trajectory_files_read_tum(est), ref_rows = trajectory_files_read_tum(ref);
  std::ifstream csv(dir.path() / "mcl_implicit_M20_trajectory.csv");
  std::string line;
  std::getline(csv, line);  // header
  std::size_t step = 0, with_heading = 0;
  for (; std::getline(csv, line); ++step) {
    // step,time_s,truth_x,truth_y,truth_heading,est_x,est_y,est_heading,...
    std::vector<double> v;
    std::istringstream fields(line);
    for (std::string f; std::getline(fields, f, ',') && v.size() < 8;) v.push_back(std::stod(f));
    ASSERT_LT(step, est_rows.size());
    const auto& e = est_rows[step];
    ASSERT_NEAR(e[0], v[1], 1e-3) << "step " << step;  // the CSV rounds to 6 or 3 decimals
    ASSERT_NEAR(e[1], v[5], 1e-6) << "step " << step;
    ASSERT_NEAR(e[2], v[6], 1e-6) << "step " << step;
    ASSERT_LT(trajectory_files_angle_gap(e[3], v[7]), 1e-6) << "step " << step;
    if (!std::isfinite(v[2]) || !std::isfinite(v[4])) continue;
    ASSERT_LT(with_heading, ref_rows.size());
    const auto& t = ref_rows[with_heading++];
    ASSERT_NEAR(t[0], v[1], 1e-3) << "step " << step;
    ASSERT_NEAR(t[1], v[2], 1e-6) << "step " << step;
    ASSERT_LT(trajectory_files_angle_gap(t[3], v[4]), 1e-6) << "step " << step;
  }
  EXPECT_EQ(step, est_rows.size());
  EXPECT_EQ(with_heading, ref_rows.size());
  EXPECT_GT(with_heading, 100u);
  const auto ape = trajectory_files_ape(ref, est);
  EXPECT_NEAR(ape.rotation_rmse_rad, j["heading_rmse_rad"].get<double>(), 1e-9);
}

TEST(TrajectoryFiles, LaserMclFilesScoreAsTheRunItself) {
  TempDir dir("trajectory_files_laser");
  const std::string est = (dir.path() / "est.tum").string(),
                    ref = (dir.path() / "truth.tum").string();
  const auto r = run_cli(
      "mcl --sensor laser --quiet --json --runs 1 -M 20 --max-updates 12 --data " +
      std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz --trajectory " + est +
      " --truth-trajectory " + ref);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto ape = trajectory_files_ape(ref, est);
  EXPECT_EQ(ape.count, 12);
  EXPECT_NEAR(ape.translation_rmse, j["position_rmse_m"]["mean"].get<double>(), 1e-9);
  EXPECT_NEAR(ape.rotation_rmse_rad, j["heading_rmse_rad"]["mean"].get<double>(), 1e-9);
}

TEST(TrajectoryFiles, SlamFilesScoreAsTheRunItself) {
  TempDir dir("trajectory_files_slam");
  const std::string est = (dir.path() / "est.tum").string(),
                    ref = (dir.path() / "truth.tum").string();
  const auto r = run_cli("slam --method ekf --datasets 1 --quiet --json --trajectory " + est +
                         " --truth-trajectory " + ref);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto ape = trajectory_files_ape(ref, est);
  // The files start at the known initial pose (error 0), which the run's score leaves out.
  const int steps = j["steps_per_dataset"].get<int>();
  ASSERT_EQ(ape.count, steps + 1);
  const double scale = std::sqrt(static_cast<double>(steps + 1) / steps);
  EXPECT_NEAR(ape.translation_rmse * scale, j["rmse_pose_m"].get<double>(), 1e-9);
}

TEST(TrajectoryFiles, BadFileNamesAreRefusedBeforeTheRun) {
  for (const std::string cmd : {"mcl", "slam"}) {
    for (const std::string flag : {"--trajectory", "--truth-trajectory"}) {
      const auto empty = run_cli(cmd + " " + flag + " ''");
      EXPECT_EQ(empty.code, 2) << cmd << " " << flag;
      EXPECT_NE(empty.err.find(flag), std::string::npos) << empty.err;
      const auto gone = run_cli(cmd + " " + flag + " /no/such/folder/x.tum");
      EXPECT_EQ(gone.code, 2) << cmd << " " << flag;
      EXPECT_NE(gone.err.find("/no/such/folder"), std::string::npos) << gone.err;
    }
  }
}

}  // namespace
