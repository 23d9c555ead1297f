// `implicit slam --sensor laser --g2o FILE`: the first run's pose graph. Its vertices are the
// run's trajectory (the --trajectory file's poses), and its edges are the odometry the filter was
// given: scored against the reference increments (the --truth-trajectory file) they give back the
// run's own odometry relation error, which the command computes from that odometry in memory.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

constexpr double kG2oCliPi = 3.14159265358979323846;

/// The rows of a file as numbers after their first field (a tag or, for TUM, the time).
std::vector<std::vector<double>> g2o_cli_rows(const std::string& file, const std::string& tag) {
  std::ifstream in(file);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string first;
    fields >> first;
    if (!tag.empty() && first != tag) continue;
    std::vector<double> v;
    if (tag.empty()) v.push_back(std::stod(first));
    for (std::string f; fields >> f;) v.push_back(std::stod(f));
    rows.push_back(v);
  }
  return rows;
}

double g2o_cli_wrap(double a) { return std::remainder(a, 2.0 * kG2oCliPi); }

TEST(GridSlamG2oCli, VerticesAreTheTrajectoryAndEdgesTheRunsOdometry) {
  TempDir dir("grid_slam_g2o_cli");
  const std::string graph = (dir.path() / "run.g2o").string();
  const std::string est = (dir.path() / "est.tum").string();
  const std::string ref = (dir.path() / "ref.tum").string();
  const auto r = run_cli(
      "slam --sensor laser --quiet --json --max-scans 60 -M 3 --method implicit --threads 1 "
      "--data " +
      std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz --g2o " + graph +
      " --trajectory " + est + " --truth-trajectory " + ref);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto n = j["scans_processed"].get<std::size_t>();
  const auto vertices = g2o_cli_rows(graph, "VERTEX_SE2");
  const auto edges = g2o_cli_rows(graph, "EDGE_SE2");
  const auto est_rows = g2o_cli_rows(est, ""), ref_rows = g2o_cli_rows(ref, "");
  ASSERT_GT(n, 5u);
  ASSERT_EQ(vertices.size(), n);
  ASSERT_EQ(edges.size(), n - 1);
  ASSERT_EQ(est_rows.size(), n);  // no scan time went back in these scans: nothing left out
  ASSERT_EQ(ref_rows.size(), n);
  for (std::size_t k = 0; k < n; ++k) {
    // TUM: t x y z qx qy qz qw; the heading is 2 atan2(qz, qw).
    EXPECT_EQ(vertices[k][0], static_cast<double>(k));
    EXPECT_NEAR(vertices[k][1], est_rows[k][1], 1e-12) << "vertex " << k;
    EXPECT_NEAR(vertices[k][2], est_rows[k][2], 1e-12) << "vertex " << k;
    EXPECT_NEAR(g2o_cli_wrap(vertices[k][3] - 2 * std::atan2(est_rows[k][6], est_rows[k][7])), 0.0,
                1e-12)
        << "vertex " << k;
  }
  // The relation metric of the edges against the reference increments, as the run scores its
  // odometry (spec §3.13.4): E = between(ref_rel, edge), |t_E| = |edge_t - ref_rel_t|.
  double translation = 0.0, rotation = 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const auto& e = edges[k];
    ASSERT_EQ(e.size(), 11u);
    EXPECT_EQ(e[0], static_cast<double>(k));
    EXPECT_EQ(e[1], static_cast<double>(k + 1));
    const double h0 = 2 * std::atan2(ref_rows[k][6], ref_rows[k][7]);
    const double h1 = 2 * std::atan2(ref_rows[k + 1][6], ref_rows[k + 1][7]);
    const double dx = ref_rows[k + 1][1] - ref_rows[k][1], dy = ref_rows[k + 1][2] - ref_rows[k][2];
    const double rx = std::cos(h0) * dx + std::sin(h0) * dy;
    const double ry = -std::sin(h0) * dx + std::cos(h0) * dy;
    translation += std::hypot(e[2] - rx, e[3] - ry);
    rotation += std::abs(g2o_cli_wrap(e[4] - (h1 - h0))) * 180.0 / kG2oCliPi;
    Eigen::Matrix3d info;
    info << e[5], e[6], e[7], e[6], e[8], e[9], e[7], e[9], e[10];
    EXPECT_EQ(Eigen::LLT<Eigen::Matrix3d>(info).info(), Eigen::Success) << "edge " << k;
  }
  // The files round-trip their doubles; the sums differ from the run's by rounding only.
  EXPECT_NEAR(translation / static_cast<double>(n - 1),
              j["odometry_relation_translation_m"].get<double>(), 1e-9);
  EXPECT_NEAR(rotation / static_cast<double>(n - 1),
              j["odometry_relation_rotation_deg"].get<double>(), 1e-7);
}

TEST(GridSlamG2oCli, BadFileAndTheOtherSensorAreRefusedBeforeTheRun) {
  const std::string aces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const Row rows[] = {
      {"slam --sensor laser --g2o '' --data " + aces, 2, "--g2o"},
      {"slam --sensor laser --g2o /no/such/folder/run.g2o --data " + aces, 2, "/no/such/folder"},
      // The landmark path writes one too (landmark_slam_g2o_cli_test.cpp), refused alike.
      {"slam --g2o /no/such/folder/run.g2o --datasets 1", 2, "/no/such/folder"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_EQ(r.out, "") << row.args;  // refused before any run
  }
}

}  // namespace
