// Pose graphs and their g2o files (robot/pose_graph.hpp).
#include "implicit/robot/pose_graph.hpp"

#include <cmath>
#include <string>

#include <fmt/format.h>
#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"

namespace implicit::robot {
namespace {

/// Symmetric within 1e-9 of the largest entry and positive definite (Cholesky succeeds).
template <typename M>
bool pose_graph_spd(const M& m) {
  if (!m.allFinite()) return false;
  const double scale = m.cwiseAbs().maxCoeff();
  if (!((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) return false;
  const Eigen::LLT<M> llt(0.5 * (m + m.transpose()));
  return llt.info() == Eigen::Success;
}

double pose_graph_wrap(double angle) { return std::remainder(angle, 2.0 * kPi); }

}  // namespace

void PoseGraph2::validate(std::string_view what) const {
  for (std::size_t k = 0; k < poses.size(); ++k)
    require(poses[k].allFinite(), "{}: vertex {}: expected a finite pose, got ({}, {}, {})", what,
            k, poses[k](0), poses[k](1), poses[k](2));
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge2& e = edges[k];
    require(e.from < poses.size() && e.to < poses.size() && e.from != e.to,
            "{}: edge {}: expected two different vertices below {}, got {} -> {}", what, k,
            poses.size(), e.from, e.to);
    require(e.measurement.allFinite(), "{}: edge {} ({} -> {}): expected a finite measurement",
            what, k, e.from, e.to);
    require(pose_graph_spd(e.information),
            "{}: edge {} ({} -> {}): expected a symmetric positive definite information matrix",
            what, k, e.from, e.to);
  }
  for (std::size_t k = 0; k < landmarks.size(); ++k)
    require(landmarks[k].allFinite(), "{}: landmark {}: expected a finite position, got ({}, {})",
            what, k, landmarks[k](0), landmarks[k](1));
  for (std::size_t k = 0; k < point_edges.size(); ++k) {
    const PoseGraphPointEdge2& e = point_edges[k];
    require(e.pose < poses.size() && e.landmark < landmarks.size(),
            "{}: point edge {}: expected a pose below {} and a landmark below {}, got {} -> {}",
            what, k, poses.size(), landmarks.size(), e.pose, e.landmark);
    require(e.measurement.allFinite(),
            "{}: point edge {} ({} -> landmark {}): expected a finite "
            "measurement",
            what, k, e.pose, e.landmark);
    require(pose_graph_spd(e.information),
            "{}: point edge {} ({} -> landmark {}): expected a symmetric positive definite "
            "information matrix",
            what, k, e.pose, e.landmark);
  }
}

Mat3 g2o_information(const Mat3& covariance, const Pose& measurement) {
  require(pose_graph_spd(covariance),
          "g2o_information: expected a symmetric positive definite covariance");
  // e = A (a - z) with A = diag(R(z_theta)^T, 1), orthogonal: (A Sigma A^T)^-1 = A Sigma^-1 A^T.
  const double c = std::cos(measurement(2)), s = std::sin(measurement(2));
  Mat3 a;
  a << c, s, 0.0,  //
      -s, c, 0.0,  //
      0.0, 0.0, 1.0;
  const Mat3 information = a * covariance.llt().solve(Mat3::Identity()) * a.transpose();
  return 0.5 * (information + information.transpose());  // exactly symmetric, as written
}

Mat3 world_noise_edge_information(const Mat3& world_covariance, const Pose& from,
                                  const Pose& measurement) {
  require(pose_graph_spd(world_covariance),
          "world_noise_edge_information: expected a symmetric positive definite covariance");
  require(from.allFinite(), "world_noise_edge_information: expected a finite pose");
  // The increment (R(theta)^T (p_to - p_from), theta_to - theta_from) moves with the noise w by
  // B w, B = diag(R(theta_from)^T, 1), given the from pose.
  const double c = std::cos(from(2)), s = std::sin(from(2));
  Mat3 b;
  b << c, s, 0.0,  //
      -s, c, 0.0,  //
      0.0, 0.0, 1.0;
  const Mat3 local = b * world_covariance * b.transpose();
  return g2o_information(0.5 * (local + local.transpose()), measurement);
}

PoseGraphPointEdge2 range_bearing_point_edge(std::size_t pose, std::size_t landmark,
                                             const Measurement& z, const Mat2& covariance) {
  require(z.allFinite() && z(0) > 0.0,
          "range_bearing_point_edge: expected a finite detection with range > 0, got ({}, {})",
          z(0), z(1));
  require(pose_graph_spd(covariance),
          "range_bearing_point_edge: expected a symmetric positive definite sensor covariance");
  // Bearing b is measured from the right (pi/2 ahead): the direction in the pose's frame is
  // phi = b - pi/2, so the point is r (cos phi, sin phi) = r (sin b, -cos b).
  const double r = z(0), c = std::cos(z(1)), s = std::sin(z(1));
  PoseGraphPointEdge2 e;
  e.pose = pose;
  e.landmark = landmark;
  e.measurement = Landmark(r * s, -r * c);
  Mat2 j;
  j << s, r * c,  //
      -c, r * s;
  const Mat2 cov = j * covariance * j.transpose();
  const Mat2 information = cov.llt().solve(Mat2::Identity());
  e.information = 0.5 * (information + information.transpose());
  return e;
}

Mat3 odometry_edge_information(const OdometryModel& model, const OdometryDelta& u) {
  return g2o_information(model.process_covariance(Pose::Zero(), u), u);
}

PoseGraph2 odometry_pose_graph(const std::vector<Pose>& poses, const std::vector<Pose>& odometry,
                               const OdometryModel& model) {
  require(!poses.empty() && poses.size() == odometry.size(),
          "odometry_pose_graph: expected as many odometry poses as poses (at least one), got {} "
          "poses and {} odometry poses",
          poses.size(), odometry.size());
  PoseGraph2 g;
  g.poses = poses;
  for (std::size_t k = 0; k < odometry.size(); ++k)
    require(odometry[k].allFinite(), "odometry_pose_graph: odometry pose {}: expected finite", k);
  for (std::size_t k = 1; k < odometry.size(); ++k) {
    const OdometryDelta u = between(odometry[k - 1], odometry[k]);
    g.edges.push_back({k - 1, k, u, odometry_edge_information(model, u)});
  }
  g.validate("odometry_pose_graph");
  return g;
}

std::string format_g2o(const PoseGraph2& graph) {
  graph.validate("format_g2o");
  std::string out;
  for (std::size_t k = 0; k < graph.poses.size(); ++k) {
    const Pose& p = graph.poses[k];
    out += fmt::format("VERTEX_SE2 {} {} {} {}\n", k, p(0), p(1), pose_graph_wrap(p(2)));
  }
  const std::size_t first_landmark = graph.poses.size();
  for (std::size_t k = 0; k < graph.landmarks.size(); ++k)
    out += fmt::format("VERTEX_XY {} {} {}\n", first_landmark + k, graph.landmarks[k](0),
                       graph.landmarks[k](1));
  for (const PoseGraphEdge2& e : graph.edges) {
    const Pose& z = e.measurement;
    const Mat3& i = e.information;
    out += fmt::format("EDGE_SE2 {} {} {} {} {} {} {} {} {} {} {}\n", e.from, e.to, z(0), z(1),
                       pose_graph_wrap(z(2)), i(0, 0), i(0, 1), i(0, 2), i(1, 1), i(1, 2), i(2, 2));
  }
  for (const PoseGraphPointEdge2& e : graph.point_edges) {
    const Mat2& i = e.information;
    out += fmt::format("EDGE_SE2_XY {} {} {} {} {} {} {}\n", e.pose, first_landmark + e.landmark,
                       e.measurement(0), e.measurement(1), i(0, 0), i(0, 1), i(1, 1));
  }
  return out;
}

void write_g2o(const std::filesystem::path& path, const PoseGraph2& graph,
               const std::string& flag) {
  const std::string text = format_g2o(graph);  // validated before the file is opened
  OutputFile out(path, OutputFile::Mode::kReplace, flag);
  out.stream() << text;
  out.commit();
}

}  // namespace implicit::robot
