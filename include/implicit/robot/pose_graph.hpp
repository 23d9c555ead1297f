#pragma once
// A planar pose graph and its g2o file: the estimated poses as vertices (VERTEX_SE2) and the
// odometry between consecutive poses as edges (EDGE_SE2), each with the information matrix of
// the motion noise the filter assumed. For optimising a run afterwards with g2o, GTSAM's readG2o
// or any other reader of the format (docs/formats.md, "Pose graphs (g2o)").
//
//   robot::OdometryModel model(alphas, floor_std);             // the filter's motion model
//   robot::PoseGraph2 g = robot::odometry_pose_graph(estimate, odometry, model);
//   robot::write_g2o("run.g2o", g);                            // whole or not at all
//
// Any filter can fill a PoseGraph2 itself (its poses, and per edge the increment and the
// information of its own motion noise); g2o_information turns a covariance of the increment into
// the information g2o expects.
//
// Landmarks (for landmark SLAM's post-optimisation) are VERTEX_XY vertices numbered after the
// poses, each observation an EDGE_SE2_XY: the landmark in the observing pose's frame, whose g2o
// error is X_i^-1 l - z in that same frame, so its information is simply the inverse covariance of
// the point. range_bearing_point_edge converts a range-bearing detection to that point; its
// covariance is the sensor's pushed through the conversion's Jacobian (first order).
//
// g2o's error of an edge (i, j) with measurement Z is e = t2v(Z^-1 (X_i^-1 X_j)): the difference
// of the two increments expressed in the frame Z reaches, not in X_i's. For an increment a with
// covariance Sigma in X_i's frame (what the odometry model gives at the origin), e = A (a - z)
// with A = diag(R(z_theta)^T, 1) exactly, so the information is (A Sigma A^T)^-1 = A Sigma^-1 A^T.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// One relative-pose constraint: pose `to` seen from pose `from`.
struct PoseGraphEdge2 {
  std::size_t from = 0, to = 0;
  Pose measurement = Pose::Zero();      ///< (dx [m], dy [m], dtheta [rad]) in `from`'s frame
  Mat3 information = Mat3::Identity();  ///< inverse covariance of g2o's error of this edge
};

/// One landmark observation: landmarks[landmark] seen from poses[pose].
struct PoseGraphPointEdge2 {
  std::size_t pose = 0, landmark = 0;
  Landmark measurement = Landmark::Zero();  ///< (x [m], y [m]) in the pose's frame
  Mat2 information = Mat2::Identity();      ///< inverse covariance of that point
};

/// Vertex k is poses[k] (ids 0, 1, 2, ...), then landmark k is vertex poses.size() + k.
struct PoseGraph2 {
  std::vector<Pose> poses;
  std::vector<PoseGraphEdge2> edges;
  std::vector<Landmark> landmarks;
  std::vector<PoseGraphPointEdge2> point_edges;
  /// Throws InvalidArgument naming `what` unless every pose, landmark and measurement is finite,
  /// every edge joins two different vertices that exist (a point edge: a pose and a landmark),
  /// and every information matrix is symmetric (within 1e-9 of its largest entry) and positive
  /// definite.
  void validate(std::string_view what) const;
};

/// The information of an edge whose increment has covariance `covariance` in the `from` pose's
/// frame: (A Sigma A^T)^-1 with A = diag(R(measurement theta)^T, 1) (see the header comment).
/// Throws InvalidArgument when the covariance is not symmetric positive definite.
Mat3 g2o_information(const Mat3& covariance, const Pose& measurement);

/// The information of an edge from pose `from` whose `to` pose has the additive noise
/// `world_covariance` in the world frame (x_to = f(x_from, u) + w, as the Ute and unicycle
/// models): the increment's covariance in `from`'s frame is B Sigma B^T with
/// B = diag(R(from theta)^T, 1), then g2o_information.
Mat3 world_noise_edge_information(const Mat3& world_covariance, const Pose& from,
                                  const Pose& measurement);

/// The point edge of a range-bearing detection z = (r, b) in RangeBearingSensor's convention
/// (bearing pi/2 straight ahead): the point r (sin b, -cos b) in the pose's frame, its information
/// (J Sigma J^T)^-1 with J = [[sin b, r cos b], [-cos b, r sin b]] the conversion's Jacobian
/// (first order in the noise). Throws InvalidArgument unless z is finite with r > 0 and
/// `covariance` is symmetric positive definite.
PoseGraphPointEdge2 range_bearing_point_edge(std::size_t pose, std::size_t landmark,
                                             const Measurement& z, const Mat2& covariance);

/// The information of the odometry increment u under `model`'s Gaussian form: the covariance is
/// model.process_covariance at the origin (J diag(var_rot1, var_trans, var_rot2) J^T plus the
/// floor), which the floor keeps positive definite also for a robot standing still.
Mat3 odometry_edge_information(const OdometryModel& model, const OdometryDelta& u);

/// Vertices `poses` (the estimate), edges k -> k+1 with the odometry increments
/// between(odometry[k], odometry[k+1]) and their odometry_edge_information. Throws
/// InvalidArgument unless both have the same size, at least one pose, all finite.
PoseGraph2 odometry_pose_graph(const std::vector<Pose>& poses, const std::vector<Pose>& odometry,
                               const OdometryModel& model);

/// The g2o text: `VERTEX_SE2 id x y theta` per pose, `VERTEX_XY id x y` per landmark, then
/// `EDGE_SE2 from to dx dy dtheta I11 I12 I13 I22 I23 I33` per edge (the upper triangle of the
/// information, row by row) and `EDGE_SE2_XY pose landmark x y I11 I12 I22` per point edge. Angles
/// are wrapped to [-pi, pi]; every number in its shortest exact form. Validates the graph first.
std::string format_g2o(const PoseGraph2& graph);

/// format_g2o written under a temporary name and renamed when complete (OutputFile); `flag` is
/// named first in a write error.
void write_g2o(const std::filesystem::path& path, const PoseGraph2& graph,
               const std::string& flag = "write_g2o");

}  // namespace implicit::robot
