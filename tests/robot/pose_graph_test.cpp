// Pose graphs as g2o files: a 3-pose graph against a file written by hand (its information
// matrices worked out on paper from the odometry model), edges that compose back to the odometry
// when the file is parsed again, the information against a Monte Carlo of g2o's own error under
// the filter's motion noise, the whole-or-nothing write, and every invalid graph refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/pose_graph.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

/// One line of a g2o file: its tag, and every other field as a number.
struct PoseGraphTestLine {
  std::string tag;
  std::vector<double> fields;
};

/// Parses g2o text by hand (independent of the writer): whitespace-separated fields, one element
/// per line.
std::vector<PoseGraphTestLine> pose_graph_test_parse(const std::string& text) {
  std::vector<PoseGraphTestLine> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    PoseGraphTestLine l;
    if (!(fields >> l.tag)) continue;
    for (std::string f; fields >> f;) l.fields.push_back(std::stod(f));
    lines.push_back(l);
  }
  return lines;
}

// Odometry along x by 1 m, then 1 m ahead with a quarter turn. With alphas (0, 0.01, 0.03, 0) and
// a floor of 0.1 on each axis, both steps have rot1 = 0, trans = 1: var_rot1 = alpha2 = 0.01,
// var_trans = alpha3 = 0.03, var_rot2 = alpha2 = 0.01, J = [0 1 0; 1 0 0; 1 0 1] at the origin, so
//   Sigma = J diag(0.01, 0.03, 0.01) J^T + 0.01 I = [0.04 0 0; 0 0.02 0.01; 0 0.01 0.03].
// Edge 0 -> 1 (dtheta = 0): information Sigma^-1 = [25 0 0; 0 60 -20; 0 -20 40].
// Edge 1 -> 2 (dtheta = pi/2): g2o's error is in the frame turned by pi/2, where x is the
// odometry's y and y its -x: A Sigma A^T = [0.02 0 0.01; 0 0.04 0; 0.01 0 0.03], information
// [60 0 -20; 0 25 0; -20 0 40].
const OdometryModel& pose_graph_test_model() {
  static const OdometryModel model({.alpha1 = 0.0, .alpha2 = 0.01, .alpha3 = 0.03, .alpha4 = 0.0},
                                   Vec<3>(0.1, 0.1, 0.1));
  return model;
}
const std::vector<Pose> kPoseGraphTestOdometry = {Pose(0, 0, 0), Pose(1, 0, 0),
                                                  Pose(2, 0, kPi / 2)};
// The estimate (vertices): anything finite; the third heading is past pi, written wrapped.
const std::vector<Pose> kPoseGraphTestEstimate = {Pose(0, 0, 0), Pose(0.875, 0.125, -0.25),
                                                  Pose(2.5, -0.5, 4.0)};
const char* const kPoseGraphTestExpected =
    "VERTEX_SE2 0 0 0 0\n"
    "VERTEX_SE2 1 0.875 0.125 -0.25\n"
    "VERTEX_SE2 2 2.5 -0.5 -2.2831853071795862\n"
    "EDGE_SE2 0 1 1 0 0 25 0 0 60 -20 40\n"
    "EDGE_SE2 1 2 1 0 1.5707963267948966 60 0 -20 25 0 40\n";

TEST(PoseGraph, ThreePosesAsTheFileWrittenByHand) {
  const PoseGraph2 g =
      odometry_pose_graph(kPoseGraphTestEstimate, kPoseGraphTestOdometry, pose_graph_test_model());
  const auto got = pose_graph_test_parse(format_g2o(g));
  const auto want = pose_graph_test_parse(kPoseGraphTestExpected);
  ASSERT_EQ(got.size(), want.size()) << format_g2o(g);
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].tag, want[k].tag) << "line " << k + 1;
    ASSERT_EQ(got[k].fields.size(), want[k].fields.size()) << "line " << k + 1;
    // The hand values are exact; the program's pass through a 3x3 inverse and cos(pi/2) =
    // 6e-17 leaves rounding of a few ulps of the largest entry (60).
    for (std::size_t f = 0; f < want[k].fields.size(); ++f)
      EXPECT_NEAR(got[k].fields[f], want[k].fields[f], 1e-12 * 60)
          << "line " << k + 1 << " field " << f + 1;
  }
}

TEST(PoseGraph, EdgesComposeBackToTheOdometry) {
  // A wandering odometry with turns past pi (unwrapped headings), backing up and standing still.
  std::vector<Pose> odometry{Pose(3.0, -2.0, 0.5)}, estimate{Pose(3.0, -2.0, 0.5)};
  const std::vector<Pose> steps = {Pose(0.4, 0.02, 0.3), Pose(0.5, -0.1, 2.9), Pose(-0.3, 0.0, 0.1),
                                   Pose(0.0, 0.0, 0.0),  Pose(0.2, 0.3, -3.5), Pose(1.0, 0.0, 3.1)};
  for (const Pose& s : steps) {
    odometry.push_back(compose(odometry.back(), s));
    estimate.push_back(odometry.back() + Pose(0.01, -0.02, 0.03));
  }
  const OdometryModel model({.alpha1 = 0.002, .alpha2 = 0.002, .alpha3 = 0.002, .alpha4 = 0.002});
  const std::string text = format_g2o(odometry_pose_graph(estimate, odometry, model));
  std::map<std::size_t, Pose> vertices;
  std::vector<PoseGraphTestLine> edges;
  for (const auto& l : pose_graph_test_parse(text)) {
    if (l.tag == "VERTEX_SE2") {
      ASSERT_EQ(l.fields.size(), 4u);
      vertices[static_cast<std::size_t>(l.fields[0])] = Pose(l.fields[1], l.fields[2], l.fields[3]);
    } else {
      ASSERT_EQ(l.tag, "EDGE_SE2");
      ASSERT_EQ(l.fields.size(), 11u);
      edges.push_back(l);
    }
  }
  ASSERT_EQ(vertices.size(), odometry.size());
  ASSERT_EQ(edges.size(), steps.size());
  Pose chained = odometry[0];
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto& f = edges[k].fields;
    EXPECT_EQ(f[0], static_cast<double>(k));
    EXPECT_EQ(f[1], static_cast<double>(k + 1));
    chained = compose(chained, Pose(f[2], f[3], f[4]));
    // Composing the file's edges from the first odometry pose reaches every odometry pose (the
    // heading modulo 2 pi: the file wraps it); rounding grows by a few ulps per edge.
    EXPECT_NEAR(chained(0), odometry[k + 1](0), 1e-12) << "edge " << k;
    EXPECT_NEAR(chained(1), odometry[k + 1](1), 1e-12) << "edge " << k;
    EXPECT_NEAR(std::remainder(chained(2) - odometry[k + 1](2), 2 * kPi), 0.0, 1e-12) << k;
    // The information, read back, is the model's (symmetric, positive definite).
    Mat3 info;
    info << f[5], f[6], f[7], f[6], f[8], f[9], f[7], f[9], f[10];
    const Mat3 want = odometry_edge_information(model, steps[k]);
    EXPECT_LE((info - want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff()) << k;
    EXPECT_GT(info.determinant(), 0.0) << k;
  }
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    EXPECT_EQ(vertices[k].head<2>(), estimate[k].head<2>()) << "vertex " << k;
    EXPECT_NEAR(std::remainder(vertices[k](2) - estimate[k](2), 2 * kPi), 0.0, 1e-15) << k;
    EXPECT_LE(std::abs(vertices[k](2)), kPi) << "vertex " << k;
  }
}

// The derivation, checked by simulation: draws of the filter's motion noise (the odometry
// sampler plus the floor, drawn in the frame of the first pose) give g2o's error
// e = t2v(Z^-1 (X_i^-1 X_j)) = (R(z_theta)^T (p - z_xy), phi - z_theta); whitened with the edge's
// information its sample covariance must be the identity. N = 200000 draws: an entry's standard
// error is at most sqrt(2 / N) = 0.0032, and the linearised covariance of noise this small
// (heading sd about 0.03 rad) is off by O(sd^2) = 1e-3; the bound 0.02 is 6 standard errors
// plus that. Leaving out the frame change A (0.9 rad here) moves entries by 0.2 or more.
TEST(PoseGraph, InformationIsTheInverseCovarianceOfG2osError) {
  const OdometryModel model({.alpha1 = 0.001, .alpha2 = 0.001, .alpha3 = 0.001, .alpha4 = 0.001});
  const OdometryDelta z(0.8, 0.3, 0.9);
  const Mat3 info = odometry_edge_information(model, z);
  const Eigen::LLT<Mat3> llt(info);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Mat3 whiten = llt.matrixU();  // U^T U = info: U e has identity covariance
  const int n = 200000;
  Rng rng({.seed = 11, .purpose = purpose::kUser});
  Mat3 second = Mat3::Zero();
  Vec<3> sum = Vec<3>::Zero();
  const double c = std::cos(z(2)), s = std::sin(z(2));
  for (int k = 0; k < n; ++k) {
    Pose a = model.sample(Pose::Zero(), z, rng);
    a += model.floor_std().cwiseProduct(rng.normal_vector<3>());
    const Vec<3> d = a - z;
    const Vec<3> e(c * d(0) + s * d(1), -s * d(0) + c * d(1), d(2));
    const Vec<3> w = whiten * e;
    sum += w;
    second += w * w.transpose();
  }
  const Vec<3> mean = sum / n;
  const Mat3 cov = second / n - mean * mean.transpose();
  EXPECT_LE((cov - Mat3::Identity()).cwiseAbs().maxCoeff(), 0.02) << cov;
}

TEST(PoseGraph, WritesWholeFileAndRefusesBadGraphs) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("implicit_pose_graph_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const PoseGraph2 g =
      odometry_pose_graph(kPoseGraphTestEstimate, kPoseGraphTestOdometry, pose_graph_test_model());
  write_g2o(dir / "g.g2o", g);
  std::ifstream in(dir / "g.g2o");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), format_g2o(g));
  // A folder that does not exist: the error names the flag and the file; nothing is left behind.
  try {
    write_g2o(dir / "none" / "g.g2o", g, "slam --g2o");
    ADD_FAILURE() << "expected an error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("slam --g2o"));
    EXPECT_THAT(e.what(), HasSubstr("none/g.g2o"));
  }
  std::filesystem::remove_all(dir);

  const auto refused = [](const PoseGraph2& bad) {
    try {
      (void)format_g2o(bad);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  PoseGraph2 b = g;
  b.edges[1].to = 3;
  EXPECT_THAT(refused(b), HasSubstr("edge 1: expected two different vertices below 3"));
  b = g;
  b.edges[0].to = 0;
  EXPECT_THAT(refused(b), HasSubstr("edge 0"));
  b = g;
  b.poses[2](1) = NAN;
  EXPECT_THAT(refused(b), HasSubstr("vertex 2"));
  b = g;
  b.edges[0].measurement(2) = INFINITY;
  EXPECT_THAT(refused(b), HasSubstr("edge 0 (0 -> 1): expected a finite measurement"));
  b = g;
  b.edges[1].information(0, 1) = 5.0;  // not symmetric
  EXPECT_THAT(refused(b), HasSubstr("edge 1 (1 -> 2): expected a symmetric positive definite"));
  b = g;
  b.edges[0].information = -Mat3::Identity();
  EXPECT_THAT(refused(b), HasSubstr("symmetric positive definite"));
  EXPECT_THAT(
      [] {
        try {
          (void)odometry_pose_graph({Pose::Zero()}, {}, pose_graph_test_model());
        } catch (const InvalidArgument& e) {
          return std::string(e.what());
        }
        return std::string("accepted");
      }(),
      HasSubstr("got 1 poses and 0 odometry poses"));
  EXPECT_THROW((void)g2o_information(Mat3::Zero(), Pose::Zero()), InvalidArgument);
}

}  // namespace
}  // namespace implicit::robot
