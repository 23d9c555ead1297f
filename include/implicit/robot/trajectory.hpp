#pragma once
// A stamped trajectory (times and SE(3) poses) and its file formats: TUM, KITTI and relations.
//
//   robot::Trajectory ref = robot::read_tum("ref.tum");      // t x y z qx qy qz qw
//   robot::Trajectory est = robot::read_kitti("00.txt");     // 3x4 row-major, time = frame index
//   auto rel = robot::read_relations("intel.relations");     // t1 t2 x y z roll pitch yaw
//   robot::write_tum("est.tum", robot::Trajectory::from_se2(times, poses2d));
//
// A pose is a translation and a unit quaternion (Eigen's w, x, y, z; the files say qx qy qz qw).
// An SE(2) pose (x, y, heading) embeds as (x, y, 0) and a rotation by heading about z, so the
// planar estimates of mcl and slam are scored with the same code as 3-D ones.
//
// The readers are strict: every malformed line is a ParseError "file:line: expected ..., got ..."
// (column count, a field that is not a finite number, a quaternion whose norm differs from 1 by
// more than 1e-3, a KITTI rotation that is not orthonormal within 1e-3, times not strictly
// increasing, no pose at all). Quaternions within the tolerance are normalised. '#' starts a
// comment (to the end of the line); blank lines are skipped; fields are separated by spaces or
// tabs. Files may be gzip-compressed (read_text_file).

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// A rigid motion in 3-D: x -> rotation * x + translation.
struct Pose3 {
  Vec<3> translation = Vec<3>::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();

  /// (x, y, heading) as (x, y, 0) and a rotation by heading about z.
  static Pose3 from_se2(const Pose& p);
  /// R = Rz(yaw) Ry(pitch) Rx(roll), the convention of the relations files.
  static Pose3 from_rpy(const Vec<3>& translation, double roll, double pitch, double yaw);

  Pose3 inverse() const;
  Pose3 operator*(const Pose3& b) const;  ///< this, then b in this pose's frame
  Vec<3> apply(const Vec<3>& x) const { return rotation * x + translation; }
  Eigen::Matrix4d matrix() const;
  /// Angle of the rotation [rad], in [0, pi] (2 atan2(|v|, |w|): accurate near 0 and near pi).
  double rotation_angle() const;
};

/// Poses with strictly increasing times [s] (a KITTI file's times are its frame indices).
struct Trajectory {
  std::vector<double> times;
  std::vector<Pose3> poses;
  std::string source;  ///< file name, for messages (empty when made in code)

  std::size_t size() const { return times.size(); }
  bool empty() const { return times.empty(); }
  /// Planar poses (x, y, heading) at the given times (sizes must agree, times increasing).
  static Trajectory from_se2(const std::vector<double>& times, const std::vector<Pose>& poses);
  /// Throws InvalidArgument naming `what` unless sizes agree, times are finite and strictly
  /// increasing and every rotation is a unit quaternion (within 1e-9).
  void validate(std::string_view what) const;
};

/// A measured relative motion between two times (Kümmerle et al. 2009): the pose at t2 seen from
/// the pose at t1.
struct Relation {
  double t1 = 0.0, t2 = 0.0;
  Pose3 delta;
  std::size_t line = 0;  ///< line in its file (0 when made in code)
};

/// TUM RGB-D format: one pose per line, `t x y z qx qy qz qw`.
Trajectory parse_tum(std::string_view text, const std::string& name);
Trajectory read_tum(const std::filesystem::path& path);
/// Shortest round-trip representation of every number: writing and reading gives the same doubles.
std::string format_tum(const Trajectory& trajectory);
/// Written under a temporary name and renamed when complete (gzip for a .gz name).
void write_tum(const std::filesystem::path& path, const Trajectory& trajectory);

/// KITTI odometry format: 12 numbers per line, the 3x4 matrix [R | t] row by row; no times, so a
/// pose's time is its frame index (0, 1, 2, ... counting data lines).
Trajectory parse_kitti(std::string_view text, const std::string& name);
Trajectory read_kitti(const std::filesystem::path& path);

/// Relations: `t1 t2 x y z roll pitch yaw` per line (angles in radians). At least one relation;
/// t1 and t2 must differ. The order of lines is free.
std::vector<Relation> parse_relations(std::string_view text, const std::string& name);
std::vector<Relation> read_relations(const std::filesystem::path& path);

}  // namespace implicit::robot
