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
bool pose_graph_spd(const Mat3& m) {
  if (!m.allFinite()) return false;
  const double scale = m.cwiseAbs().maxCoeff();
  if (!((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) return false;
  const Eigen::LLT<Mat3> llt(0.5 * (m + m.transpose()));
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
  for (const PoseGraphEdge2& e : graph.edges) {
    const Pose& z = e.measurement;
    const Mat3& i = e.information;
    out += fmt::format("EDGE_SE2 {} {} {} {} {} {} {} {} {} {} {}\n", e.from, e.to, z(0), z(1),
                       pose_graph_wrap(z(2)), i(0, 0), i(0, 1), i(0, 2), i(1, 1), i(1, 2), i(2, 2));
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
