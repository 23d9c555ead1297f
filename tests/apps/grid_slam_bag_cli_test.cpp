// `implicit slam --sensor laser --data BAG`: grid SLAM on a ROS bag (tests/data/bags: 30 Intel
// scans). The bag's odometry is the motion input; the bag has no reference, so the scores that
// need one are null in JSON and "n/a" in text. The trajectory is checked against the bag's
// /ground_truth topic (read apart from the run) within a tolerance derived from the filter's
// motion model; the bag flags and --truth-trajectory are refused where they cannot apply.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/odometry_model.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

const std::string& grid_slam_bag() {
  static const std::string bag =
      std::string(IMPLICIT_SOURCE_DIR) + "/tests/data/bags/intel-zstd.mcap";
  return bag;
}

/// (t, x, y, heading) of each row of a TUM file.
std::vector<std::array<double, 4>> grid_slam_bag_tum(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::array<double, 4>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    double t, x, y, z, qx, qy, qz, qw;
    f >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    rows.push_back({t, x, y, 2.0 * std::atan2(qz, qw)});
  }
  return rows;
}

/// The scan of `log` at time t (exactly: the TUM file writes times in their shortest exact form).
std::size_t grid_slam_bag_scan_at(const implicit::robot::CarmenLog& log, double t) {
  for (std::size_t k = 0; k < log.scans.size(); ++k)
    if (log.scans[k].time == t) return k;
  ADD_FAILURE() << "no scan at time " << t;
  return 0;
}

// The tolerance. The filter is given the bag's odometry and draws each particle's motion from
// the odometry model (alphas 0.002 each, floor 0.005 m / 0.002 rad) around it; the scans then pull
// a particle towards where its map agrees, which for the implicit proposal is the minimum of scan
// mismatch plus that motion prior. So the best particle stays within the motion model's spread
// around the odometry: its dead-reckoning covariance P_k, propagated along the processed scans as
// P_k = F P_{k-1} F^T + Sigma_k (F the Jacobian of x ⊕ u in x, Sigma_k the model's
// process_covariance, P_0 = 0: the filter starts at the first pose). The bound at scan k is the
// odometry's own gap to the reference there (the odometry is interpolated at the scan's stamp,
// the reference is the pose at it) plus 4 sqrt(trace of P_k's position block): 4 standard
// deviations of the position spread.
TEST(GridSlamBagCli, FollowsTheReferenceWithinTheMotionModelsSpread) {
  TempDir dir("grid_slam_bag");
  const std::string est = (dir.path() / "est.tum").string();
  const std::string graph = (dir.path() / "bag.g2o").string();
  const auto r = run_cli(
      "slam --sensor laser --quiet --json --method implicit -M 8 --threads 1 "
      "--data " +
      grid_slam_bag() + " --trajectory " + est + " --g2o " + graph);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto rows = grid_slam_bag_tum(est);
  ASSERT_EQ(rows.size(), j["scans_processed"].get<std::size_t>());
  ASSERT_GT(rows.size(), 10u);  // of the 30 scans, those past the 1 m / 0.5 rad gate
  namespace robot = implicit::robot;
  const robot::CarmenLog odom = robot::read_bag_laser_log(grid_slam_bag()).log;
  robot::BagOptions ground_truth;
  ground_truth.odom_topic = "/ground_truth";
  const robot::CarmenLog truth = robot::read_bag_laser_log(grid_slam_bag(), ground_truth).log;
  const robot::OdometryModel model(
      {.alpha1 = 0.002, .alpha2 = 0.002, .alpha3 = 0.002, .alpha4 = 0.002});
  robot::Mat3 p = robot::Mat3::Zero();
  double worst = 0.0;  // the largest error as a fraction of its bound
  std::size_t previous = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::size_t k = grid_slam_bag_scan_at(odom, rows[i][0]);
    if (i > 0) {
      const robot::Pose& x = odom.laser_poses[previous];
      const robot::Pose u = robot::between(x, odom.laser_poses[k]);
      const double c = std::cos(x(2)), s = std::sin(x(2));
      robot::Mat3 f = robot::Mat3::Identity();
      f(0, 2) = -s * u(0) - c * u(1);
      f(1, 2) = c * u(0) - s * u(1);
      p = f * p * f.transpose() + model.process_covariance(x, u);
    }
    previous = k;
    const robot::Pose& ref = truth.laser_poses[grid_slam_bag_scan_at(truth, rows[i][0])];
    const double gap = (odom.laser_poses[k] - ref).head<2>().norm();
    const double bound = gap + 4.0 * std::sqrt(p(0, 0) + p(1, 1));
    const double error = std::hypot(rows[i][1] - ref(0), rows[i][2] - ref(1));
    EXPECT_LE(error, bound) << "scan " << k << " at " << rows[i][0] << " s";
    worst = std::max(worst, error / bound);
  }
  RecordProperty("worst_error_over_bound", std::to_string(worst));
  // The pose graph has one vertex per processed scan.
  std::ifstream g(graph);
  std::size_t vertices = 0;
  for (std::string line; std::getline(g, line);) vertices += line.rfind("VERTEX_SE2", 0) == 0;
  EXPECT_EQ(vertices, rows.size());
}

TEST(GridSlamBagCli, ScoresWithoutAReferenceAreNullAndNotAvailable) {
  const std::string args =
      "slam --sensor laser --quiet --method bootstrap -M 4 --max-scans 12 "
      "--data " +
      grid_slam_bag();
  const auto r = run_cli(args + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["scans_processed"].get<int>(), 1);
  for (const char* key : {"relation_translation_m", "relation_rotation_deg", "ate_m", "map_f1",
                          "map_agreement", "map_occupied_precision", "map_occupied_recall"}) {
    EXPECT_TRUE(j[key]["mean"].is_null()) << key << ": " << j[key];
    EXPECT_TRUE(j[key]["se"].is_null()) << key << ": " << j[key];
  }
  for (const char* key : {"odometry_relation_translation_m", "odometry_relation_rotation_deg",
                          "odometry_ate_m", "odometry_map_f1"})
    EXPECT_TRUE(j[key].is_null()) << key << ": " << j[key];
  for (const char* key : {"relation_translation_m", "relation_rotation_deg", "ate_m", "map_f1"})
    EXPECT_TRUE(j["per_run"][0][key].is_null()) << key;
  EXPECT_TRUE(std::isfinite(j["cpu_ms_per_scan"]["mean"].get<double>()));
  const auto text = run_cli(args);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("relation error n/a"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("trajectory error after SE(2) alignment n/a"), std::string::npos)
      << text.out;
  EXPECT_EQ(text.out.find("0.0000"), std::string::npos) << text.out;
}

TEST(GridSlamBagCli, BagFlagsAreRefusedWhereTheyCannotApply) {
  TempDir dir("grid_slam_bag_flags");
  const std::string aces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const Row rows[] = {
      {"slam --sensor laser --data " + grid_slam_bag() + " --scan-topic ''", 2, "--scan-topic"},
      {"slam --sensor laser --data " + grid_slam_bag() + " --odom-topic /nope", 1, "/nope"},
      {"slam --sensor laser --data " + aces + " --odom-topic /odom", 1, "--odom-topic"},
      {"slam --scan-topic /scan", 2, "--scan-topic"},
      // A bag has no reference poses: nothing to write.
      {"slam --sensor laser --data " + grid_slam_bag() + " --truth-trajectory " +
           (dir.path() / "t.tum").string(),
       2, "--truth-trajectory"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_EQ(r.out, "") << row.args;
  }
}

}  // namespace
