// `implicit slam --g2o FILE` on the landmark path: a ten-step unicycle log written here, whose
// detections give the EDGE_SE2_XY measurements and informations by hand (polar to Cartesian),
// whose controls give the EDGE_SE2 ones (the unicycle's increment and process noise), the
// vertices the --trajectory file's and the map the map CSV's; the first run only when there are
// more; and the flag's bad values refused.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

constexpr double kLmG2oPi = 3.14159265358979323846;

/// Each line's fields after the first (a g2o tag, a TUM time, a CSV kind), split on blanks or
/// commas, for the lines whose first field is `tag` (empty: every line but comments).
std::vector<std::vector<double>> lm_g2o_rows(const std::string& file, const std::string& tag,
                                             char separator = ' ') {
  std::ifstream in(file);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (separator != ' ')
      for (char& c : line)
        if (c == separator) c = ' ';
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

std::string lm_g2o_text(const std::string& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The detections of the log: scan k (k = 1..10) sees landmark 1 at (5 - 0.1 k, 1.2 + 0.05 k) and
// landmark 2 at (5.5, 2.0 - 0.02 k) (range [m], bearing [rad], pi/2 ahead).
struct LmG2oDetection {
  int step, id;
  double range, bearing;
};
std::vector<LmG2oDetection> lm_g2o_detections() {
  std::vector<LmG2oDetection> d;
  for (int k = 1; k <= 10; ++k) {
    d.push_back({k, 1, 5 - 0.1 * k, 1.2 + 0.05 * k});
    d.push_back({k, 2, 5.5, 2.0 - 0.02 * k});
  }
  return d;
}

/// A unicycle log: 10 steps of 0.1 s at v = 1 m/s, omega = 0.2 rad/s, a scan at each.
std::string lm_g2o_log(const TempDir& dir) {
  const std::string log = (dir.path() / "u.log").string();
  std::ofstream out(log);
  out << "vehicle unicycle dt=0.1\nlandmark 1 5 0\nlandmark 2 5 3\n"
      << "initial 0 0 0 0 0.1 0.1 0.01\n";
  for (int k = 1; k <= 10; ++k) out << "control " << 0.1 * k << " 1 0.2\n";
  const auto det = lm_g2o_detections();
  for (int k = 1; k <= 10; ++k) {
    out << "scan " << 0.1 * k << " 2\n";
    for (const auto& d : det)
      if (d.step == k) out << "obs " << d.range << " " << d.bearing << " " << d.id << "\n";
  }
  return log;
}

TEST(LandmarkSlamG2oCli, GraphOfTheFirstRunFromTheLogsControlsAndDetections) {
  TempDir dir("landmark_slam_g2o");
  const std::string log = lm_g2o_log(dir);
  const std::string graph = (dir.path() / "run.g2o").string();
  const std::string est = (dir.path() / "est.tum").string();
  const std::string base =
      "slam --method fastslam1 -M 10 --quiet --json --allow-empty --threads 1 --control-sd 0.2 0.1 "
      "--state-sd 0.05 0.05 0.01 --range-sd 0.3 --bearing-sd 2 --data " +
      log;
  const auto r = run_cli(base + " --datasets 1 --g2o " + graph + " --trajectory " + est +
                         " --out " + (dir.path() / "csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["steps_per_dataset"], 10);
  ASSERT_EQ(j["model"], "unicycle");

  // Vertices: the trajectory's poses, then the map's landmarks in the map CSV's order.
  const auto vertices = lm_g2o_rows(graph, "VERTEX_SE2");
  const auto tum = lm_g2o_rows(est, "");
  ASSERT_EQ(vertices.size(), 11u);
  ASSERT_EQ(tum.size(), 11u);
  for (std::size_t k = 0; k < 11; ++k) {
    EXPECT_EQ(vertices[k][0], static_cast<double>(k));
    EXPECT_NEAR(vertices[k][1], tum[k][1], 1e-12) << "vertex " << k;
    EXPECT_NEAR(vertices[k][2], tum[k][2], 1e-12) << "vertex " << k;
    EXPECT_NEAR(std::remainder(vertices[k][3] - 2 * std::atan2(tum[k][6], tum[k][7]), 2 * kLmG2oPi),
                0.0, 1e-12);
  }
  const auto points = lm_g2o_rows(graph, "VERTEX_XY");
  const auto map =
      lm_g2o_rows((dir.path() / "csv" / "slam_fastslam1_M10_map.csv").string(), "estimate", ',');
  ASSERT_EQ(points.size(), 2u);
  ASSERT_EQ(map.size(), 2u);
  std::map<int, double> vertex_of_id;
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(points[k][0], 11.0 + static_cast<double>(k));
    EXPECT_NEAR(points[k][1], map[k][1], 1e-7);  // the CSV has 9 significant digits
    EXPECT_NEAR(points[k][2], map[k][2], 1e-7);
    vertex_of_id[static_cast<int>(map[k][0])] = points[k][0];
  }

  // Odometry edges: the unicycle's increment over dt = 0.1 s, (v dt, 0, omega dt), and the
  // information of its noise seen from the pose: dt (diag(sd_v^2, 0, sd_omega^2) + diag(q^2))
  // (q_x = q_y: the world-frame part is the same in every frame), turned into g2o's error frame
  // by the increment's heading.
  const auto edges = lm_g2o_rows(graph, "EDGE_SE2");
  ASSERT_EQ(edges.size(), 10u);
  const double dt = 0.1;
  const Eigen::Vector3d diag(dt * (0.2 * 0.2 + 0.05 * 0.05), dt * 0.05 * 0.05,
                             dt * (0.1 * 0.1 + 0.01 * 0.01));
  const double zt = 0.2 * dt;
  Eigen::Matrix3d a;
  a << std::cos(zt), std::sin(zt), 0, -std::sin(zt), std::cos(zt), 0, 0, 0, 1;
  const Eigen::Matrix3d want = a * diag.cwiseInverse().asDiagonal() * a.transpose();
  for (std::size_t k = 0; k < 10; ++k) {
    const auto& e = edges[k];
    ASSERT_EQ(e.size(), 11u);
    EXPECT_EQ(e[0], static_cast<double>(k));
    EXPECT_EQ(e[1], static_cast<double>(k + 1));
    // The log's step lengths are differences of times written to 6 digits: dt to 1e-9.
    EXPECT_NEAR(e[2], 1.0 * dt, 1e-9) << "edge " << k;
    EXPECT_NEAR(e[3], 0.0, 1e-9) << "edge " << k;
    EXPECT_NEAR(e[4], zt, 1e-9) << "edge " << k;
    Eigen::Matrix3d info;
    info << e[5], e[6], e[7], e[6], e[8], e[9], e[7], e[9], e[10];
    EXPECT_LE((info - want).cwiseAbs().maxCoeff(), 1e-6 * want.cwiseAbs().maxCoeff())
        << "edge " << k << "\n"
        << info << "\nwant\n"
        << want;
  }

  // Landmark edges, one per detection, from the scan's pose to its landmark: the point
  // r (cos phi, sin phi), phi = b - pi/2, and the information R(phi) diag(1 / sd_r^2,
  // 1 / (r sd_b)^2) R(phi)^T (the polar covariance turned into the point's frame).
  const auto observed = lm_g2o_rows(graph, "EDGE_SE2_XY");
  const auto det = lm_g2o_detections();
  ASSERT_EQ(observed.size(), det.size());
  EXPECT_EQ(j["g2o_point_edges"], det.size());
  EXPECT_EQ(j["g2o_detections_unassociated"], 0);
  const double sd_r = 0.3, sd_b = 2.0 * kLmG2oPi / 180.0;
  for (std::size_t k = 0; k < det.size(); ++k) {
    const auto& e = observed[k];
    const LmG2oDetection& d = det[k];
    ASSERT_EQ(e.size(), 7u);
    EXPECT_EQ(e[0], d.step);
    // The map CSV names landmarks by their index among the log's landmark records (ids 1, 2).
    ASSERT_EQ(vertex_of_id.count(d.id - 1), 1u) << "detection " << k;
    EXPECT_EQ(e[1], vertex_of_id.at(d.id - 1)) << "detection " << k;
    const double phi = d.bearing - kLmG2oPi / 2;
    EXPECT_NEAR(e[2], d.range * std::cos(phi), 1e-12) << "detection " << k;
    EXPECT_NEAR(e[3], d.range * std::sin(phi), 1e-12) << "detection " << k;
    Eigen::Matrix2d rot;
    rot << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
    const Eigen::Matrix2d w =
        rot *
        Eigen::Vector2d(1 / (sd_r * sd_r), 1 / (d.range * d.range * sd_b * sd_b)).asDiagonal() *
        rot.transpose();
    Eigen::Matrix2d info;
    info << e[4], e[5], e[5], e[6];
    EXPECT_LE((info - w).cwiseAbs().maxCoeff(), 1e-9 * w.cwiseAbs().maxCoeff())
        << "detection " << k;
  }

  // More runs: the file is the first run's, the same as with one run (other seeds, other paths).
  const std::string graph2 = (dir.path() / "runs3.g2o").string();
  const auto r3 = run_cli(base + " --datasets 3 --g2o " + graph2);
  ASSERT_EQ(r3.code, 0) << r3.err;
  EXPECT_EQ(lm_g2o_text(graph2), lm_g2o_text(graph));

  // ML association keeps no record of its choices: each detection goes to the nearest landmark
  // within the gate, or is counted; the two add up to the detections.
  const auto ml = run_cli(base + " --datasets 1 --association ml --g2o " + graph2);
  ASSERT_EQ(ml.code, 0) << ml.err;
  const auto jm = nlohmann::json::parse(ml.out);
  EXPECT_EQ(lm_g2o_rows(graph2, "EDGE_SE2_XY").size(), jm["g2o_point_edges"].get<std::size_t>());
  EXPECT_EQ(jm["g2o_point_edges"].get<std::size_t>() +
                jm["g2o_detections_unassociated"].get<std::size_t>(),
            det.size());
  EXPECT_GT(jm["g2o_point_edges"].get<std::size_t>(), 0u);
}

TEST(LandmarkSlamG2oCli, BadFilesAreRefusedNamingTheFlag) {
  TempDir dir("landmark_slam_g2o_bad");
  const std::string log = lm_g2o_log(dir);
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const std::string run = "slam --method ekf --datasets 1 --quiet --allow-empty --data " + log;
  const Row rows[] = {
      {run + " --g2o ''", 2, "--g2o"},
      {run + " --g2o /no/such/folder/run.g2o", 2, "/no/such/folder"},
      // A folder that exists but cannot take the file: the write fails, naming flag and file.
      {run + " --g2o /proc/self/run.g2o", 1, "slam --g2o"},
      {run + " --g2o " + dir.path().string(), 1, dir.path().string()},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists("/proc/self/run.g2o"));
}

}  // namespace
