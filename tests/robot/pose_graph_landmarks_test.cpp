// Pose graphs with landmarks (VERTEX_XY, EDGE_SE2_XY) and edges of world-frame motion noise: a
// two-pose, one-landmark graph against a file written by hand, the point edge against the range-
// bearing sensor's own forward model, both informations against Monte Carlo estimates of g2o's
// error, and every invalid landmark part refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/pose_graph.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

struct PgLandmarkLine {
  std::string tag;
  std::vector<double> fields;
};

/// Parses g2o text by hand (independent of the writer): a tag, then numbers, one element a line.
std::vector<PgLandmarkLine> pg_landmark_parse(const std::string& text) {
  std::vector<PgLandmarkLine> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    PgLandmarkLine l;
    if (!(fields >> l.tag)) continue;
    for (std::string f; fields >> f;) l.fields.push_back(std::stod(f));
    lines.push_back(l);
  }
  return lines;
}

// Pose 0 at (1, 2) facing +y, pose 1 at (1, 3) facing -y, the landmark at (1, 4) (vertex 2).
// Edge 0 -> 1: world noise diag(0.04, 0.01, 0.02) seen from pose 0 (heading pi/2: x' = y,
// y' = -x) is diag(0.01, 0.04, 0.02); g2o's error turns it by the measurement's pi/2 back to
// diag(0.04, 0.01, 0.02): information diag(25, 100, 50).
// Sensor Sigma2 = diag(0.09, 0.01). Pose 0 sees the landmark 2 m straight ahead: z = (2, pi/2),
// the point (2, 0), its covariance diag(0.09, r^2 0.01 = 0.04): information diag(1/0.09, 25).
// Pose 1 sees it 1 m behind: z = (1, -pi/2), the point (-1, 0), covariance diag(0.09, 0.01):
// information diag(1/0.09, 100).
const char* const kPgLandmarkExpected =
    "VERTEX_SE2 0 1 2 1.5707963267948966\n"
    "VERTEX_SE2 1 1 3 -1.5707963267948966\n"
    "VERTEX_XY 2 1 4\n"
    "EDGE_SE2 0 1 1 0 1.5707963267948966 25 0 0 100 0 50\n"
    "EDGE_SE2_XY 0 2 2 0 11.111111111111111 0 25\n"
    "EDGE_SE2_XY 1 2 -1 0 11.111111111111111 0 100\n";

PoseGraph2 pg_landmark_graph() {
  PoseGraph2 g;
  g.poses = {Pose(1, 2, kPi / 2), Pose(1, 3, -kPi / 2)};
  g.landmarks = {Landmark(1, 4)};
  const Pose z(1, 0, kPi / 2);
  g.edges.push_back(
      {0, 1, z,
       world_noise_edge_information(Vec<3>(0.04, 0.01, 0.02).asDiagonal(), g.poses[0], z)});
  const Mat2 sigma2 = Vec<2>(0.09, 0.01).asDiagonal();
  g.point_edges.push_back(range_bearing_point_edge(0, 0, Measurement(2, kPi / 2), sigma2));
  g.point_edges.push_back(range_bearing_point_edge(1, 0, Measurement(1, -kPi / 2), sigma2));
  return g;
}

TEST(PoseGraphLandmarks, TwoPosesAndALandmarkAsTheFileWrittenByHand) {
  const std::string text = format_g2o(pg_landmark_graph());
  const auto got = pg_landmark_parse(text);
  const auto want = pg_landmark_parse(kPgLandmarkExpected);
  ASSERT_EQ(got.size(), want.size()) << text;
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].tag, want[k].tag) << "line " << k + 1;
    ASSERT_EQ(got[k].fields.size(), want[k].fields.size()) << "line " << k + 1;
    // The hand values are exact; cos(pi/2) = 6e-17 and the inverses leave rounding of a few ulps
    // of the largest entry (100).
    for (std::size_t f = 0; f < want[k].fields.size(); ++f)
      EXPECT_NEAR(got[k].fields[f], want[k].fields[f], 1e-12 * 100)
          << "line " << k + 1 << " field " << f + 1 << "\n"
          << text;
  }
}

// The point of a detection, in the pose's frame, is where the sensor's forward model put the
// landmark: R(theta)^T (m - p), for landmarks all around (bearings of every quadrant).
TEST(PoseGraphLandmarks, PointEdgeIsTheLandmarkInThePosesFrame) {
  const RangeBearingSensor sensor;
  const Pose pose(3.0, -2.0, 2.5);
  const double c = std::cos(pose(2)), s = std::sin(pose(2));
  for (const Landmark& m :
       {Landmark(10, 0), Landmark(-4, 7), Landmark(2, -9), Landmark(3.5, -1.5)}) {
    const Measurement z = sensor.predict(pose, m);
    const PoseGraphPointEdge2 e = range_bearing_point_edge(4, 7, z, sensor.noise_covariance());
    const Vec<2> d = m - pose.head<2>();
    EXPECT_EQ(e.pose, 4u);
    EXPECT_EQ(e.landmark, 7u);
    EXPECT_NEAR(e.measurement(0), c * d(0) + s * d(1), 1e-12) << m.transpose();
    EXPECT_NEAR(e.measurement(1), -s * d(0) + c * d(1), 1e-12) << m.transpose();
  }
}

/// The sample covariance of `n` whitened draws (an identity matrix when the whitening is right).
template <int N, typename Draw>
Mat<N> pg_landmark_whitened_covariance(const Mat<N>& information, int n, Draw&& draw) {
  const Eigen::LLT<Mat<N>> llt(information);
  EXPECT_EQ(llt.info(), Eigen::Success);
  const Mat<N> whiten = llt.matrixU();  // U^T U = information: U e has identity covariance
  Mat<N> second = Mat<N>::Zero();
  Vec<N> sum = Vec<N>::Zero();
  for (int k = 0; k < n; ++k) {
    const Vec<N> w = whiten * draw();
    sum += w;
    second += w * w.transpose();
  }
  const Vec<N> mean = sum / n;
  return second / n - mean * mean.transpose();
}

// The motion edge's information, by simulation: the Ute's process noise w ~ N(0, Sigma1) added
// in the world frame to the predicted pose, then g2o's error e = t2v(Z^-1 (X_i^-1 X_j)) =
// (R(z_theta)^T (R(theta_i)^T (p_j - p_i) - z_xy), theta_j - theta_i - z_theta), linear in w.
// Whitened with the edge's information its sample covariance must be the identity: with
// N = 200000 draws an entry's standard error is at most sqrt(2 / N) = 0.0032, and 0.02 is six
// of them (the error is exactly linear in w: no linearisation term). Leaving out either frame
// change (headings 2.2 and 0.6 rad here) moves entries by far more.
TEST(PoseGraphLandmarks, MotionInformationIsTheInverseCovarianceOfG2osError) {
  UteParams p;
  p.dt = 0.2;
  const UteModel ute(p);
  const Pose from(4.0, -1.0, 2.2);
  const Control u(3.0, 0.25);
  const Pose mean = ute.predict(from, u);
  const Pose z = between(from, mean);
  ASSERT_GT(std::abs(z(2)), 0.05);  // a turn: the measurement's frame differs from `from`'s
  const Mat3 sigma = ute.process_covariance(from, u);
  const Eigen::LLT<Mat3> root(sigma);
  const Mat3 l = root.matrixL();
  Rng rng({.seed = 12, .purpose = purpose::kUser});
  const double ci = std::cos(from(2)), si = std::sin(from(2));
  const double cz = std::cos(z(2)), sz = std::sin(z(2));
  const Mat3 cov =
      pg_landmark_whitened_covariance<3>(world_noise_edge_information(sigma, from, z), 200000, [&] {
        const Pose to = mean + l * rng.normal_vector<3>();
        const Vec<2> d = to.head<2>() - from.head<2>();
        const Vec<2> a(ci * d(0) + si * d(1), -si * d(0) + ci * d(1));
        const Vec<2> t = a - z.head<2>();
        return Vec<3>(cz * t(0) + sz * t(1), -sz * t(0) + cz * t(1), to(2) - from(2) - z(2));
      });
  EXPECT_LE((cov - Mat3::Identity()).cwiseAbs().maxCoeff(), 0.02) << cov;
}

// The point edge's information, by simulation: detections z + v, v ~ N(0, Sigma2), converted to
// the point r (sin b, -cos b); g2o's error is that point minus the measured one. The conversion
// is linearised, so the whitened covariance is the identity up to the standard error and the
// second-order terms: with N = 200000 the standard error of an entry is at most
// sqrt(2 / N) = 0.0032; the curvature terms are of relative size sd_b^2 = 1e-3 (tangential) and
// sd_r^2 sd_b^2 / (r^2 sd_b^2) = sd_r^2 / r^2 = 4e-4; 0.02 is six standard errors plus those.
// A Jacobian without the range factor (tangential sd 0.03 m instead of 0.3 m) misses by 99.
TEST(PoseGraphLandmarks, PointInformationIsTheInverseCovarianceOfThePoint) {
  const Measurement z(10.0, 2.4);
  const Mat2 sigma2 = Vec<2>(0.04, 0.03 * 0.03).asDiagonal();
  const PoseGraphPointEdge2 e = range_bearing_point_edge(0, 0, z, sigma2);
  Rng rng({.seed = 13, .purpose = purpose::kUser});
  const Mat2 cov = pg_landmark_whitened_covariance<2>(e.information, 200000, [&] {
    const double range_noise = 0.2 * rng.normal();
    const double bearing_noise = 0.03 * rng.normal();
    const Measurement zn(z(0) + range_noise, z(1) + bearing_noise);
    return Vec<2>(Vec<2>(zn(0) * std::sin(zn(1)), -zn(0) * std::cos(zn(1))) - e.measurement);
  });
  EXPECT_LE((cov - Mat2::Identity()).cwiseAbs().maxCoeff(), 0.02) << cov;
}

std::string pg_landmark_refused(const PoseGraph2& bad) {
  try {
    (void)format_g2o(bad);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(PoseGraphLandmarks, RefusesBadLandmarksAndPointEdges) {
  const PoseGraph2 g = pg_landmark_graph();
  PoseGraph2 b = g;
  b.point_edges[1].landmark = 1;
  EXPECT_THAT(
      pg_landmark_refused(b),
      HasSubstr("point edge 1: expected a pose below 2 and a landmark below 1, got 1 -> 1"));
  b = g;
  b.point_edges[0].pose = 2;
  EXPECT_THAT(pg_landmark_refused(b), HasSubstr("point edge 0"));
  b = g;
  b.landmarks[0](0) = NAN;
  EXPECT_THAT(pg_landmark_refused(b), HasSubstr("landmark 0: expected a finite position"));
  b = g;
  b.point_edges[1].measurement(1) = INFINITY;
  EXPECT_THAT(pg_landmark_refused(b),
              HasSubstr("point edge 1 (1 -> landmark 0): expected a finite"));
  b = g;
  b.point_edges[0].information(0, 1) = 3.0;  // not symmetric
  EXPECT_THAT(pg_landmark_refused(b), HasSubstr("symmetric positive definite"));
  const Mat2 sigma2 = Mat2::Identity();
  EXPECT_THROW((void)range_bearing_point_edge(0, 0, Measurement(0, 1), sigma2), InvalidArgument);
  EXPECT_THROW((void)range_bearing_point_edge(0, 0, Measurement(1, NAN), sigma2), InvalidArgument);
  EXPECT_THROW((void)range_bearing_point_edge(0, 0, Measurement(1, 1), -sigma2), InvalidArgument);
  EXPECT_THROW((void)world_noise_edge_information(Mat3::Zero(), Pose::Zero(), Pose::Zero()),
               InvalidArgument);
}

}  // namespace
}  // namespace implicit::robot
