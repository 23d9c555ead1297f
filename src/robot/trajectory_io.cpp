// Trajectory files: TUM, KITTI and relations (robot/trajectory.hpp).
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/trajectory.hpp"

namespace implicit::robot {

Pose3 Pose3::from_se2(const Pose& p) {
  Pose3 out;
  out.translation = Vec<3>(p(0), p(1), 0.0);
  out.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(p(2), Eigen::Vector3d::UnitZ()));
  return out;
}

Pose3 Pose3::from_rpy(const Vec<3>& translation, double roll, double pitch, double yaw) {
  Pose3 out;
  out.translation = translation;
  out.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  return out;
}

Pose3 Pose3::inverse() const {
  Pose3 out;
  out.rotation = rotation.conjugate();
  out.translation = -(out.rotation * translation);
  return out;
}

Pose3 Pose3::operator*(const Pose3& b) const {
  Pose3 out;
  out.rotation = rotation * b.rotation;
  // Products of unit quaternions drift from norm 1 by rounding; long chains of relative motions
  // would carry it into every later angle.
  out.rotation.normalize();
  out.translation = rotation * b.translation + translation;
  return out;
}

Eigen::Matrix4d Pose3::matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation.toRotationMatrix();
  m.topRightCorner<3, 1>() = translation;
  return m;
}

double Pose3::rotation_angle() const {
  return 2.0 * std::atan2(rotation.vec().norm(), std::abs(rotation.w()));
}

Trajectory Trajectory::from_se2(const std::vector<double>& times, const std::vector<Pose>& poses) {
  require(times.size() == poses.size(),
          "trajectory: expected as many times as poses, got {} times and {} poses", times.size(),
          poses.size());
  Trajectory out;
  out.times = times;
  out.poses.reserve(poses.size());
  for (const Pose& p : poses) out.poses.push_back(Pose3::from_se2(p));
  out.validate("trajectory");
  return out;
}

void Trajectory::validate(std::string_view what) const {
  require(times.size() == poses.size(),
          "{}: expected as many times as poses, got {} times and {} poses", what, times.size(),
          poses.size());
  for (std::size_t i = 0; i < times.size(); ++i) {
    require(std::isfinite(times[i]), "{}: pose {}: expected a finite time, got {}", what, i,
            times[i]);
    require(i == 0 || times[i] > times[i - 1],
            "{}: pose {}: expected a time after {} (times must increase), got {}", what, i,
            i == 0 ? 0.0 : times[i - 1], times[i]);
    require(poses[i].translation.allFinite() && poses[i].rotation.coeffs().allFinite(),
            "{}: pose {}: expected finite numbers", what, i);
    require(std::abs(poses[i].rotation.norm() - 1.0) <= 1e-9,
            "{}: pose {}: expected a unit quaternion, got norm {}", what, i,
            poses[i].rotation.norm());
  }
}

namespace {

constexpr double kTrajectoryIoUnitTolerance = 1e-3;
constexpr std::array<const char*, 8> kTrajectoryIoTumFields{"t",  "x",  "y",  "z",
                                                            "qx", "qy", "qz", "qw"};
constexpr std::array<const char*, 12> kTrajectoryIoKittiFields{
    "r11", "r12", "r13", "t1", "r21", "r22", "r23", "t2", "r31", "r32", "r33", "t3"};
constexpr std::array<const char*, 8> kTrajectoryIoRelationFields{"t1", "t2",   "x",     "y",
                                                                 "z",  "roll", "pitch", "yaw"};

/// The data lines of a text: '#' starts a comment, blank lines are skipped, fields are separated
/// by spaces and tabs; each data line is handed to `row` with its 1-based line number.
template <typename Row>
void trajectory_io_for_each_row(std::string_view text, Row&& row) {
  std::size_t line_no = 0;
  std::vector<std::string_view> fields;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    ++line_no;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos)
      line = line.substr(0, hash);
    fields.clear();
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      const std::size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
      if (i > start) fields.push_back(line.substr(start, i - start));
    }
    if (!fields.empty()) row(line_no, fields);
  }
}

/// The fields of one data line as finite numbers; `names` gives the expected count and names.
template <std::size_t N>
std::array<double, N> trajectory_io_numbers(const std::vector<std::string_view>& fields,
                                            const std::array<const char*, N>& names,
                                            const std::string& name, std::size_t line) {
  if (fields.size() != N) {
    throw ParseError(fmt::format("{}:{}: expected {} fields ({}), got {}", name, line, N,
                                 fmt::join(names, " "), fields.size()));
  }
  std::array<double, N> out{};
  for (std::size_t k = 0; k < N; ++k) {
    const std::string field(fields[k]);
    char* end = nullptr;
    const double v = std::strtod(field.c_str(), &end);
    if (end != field.c_str() + field.size() || !std::isfinite(v))
      throw ParseError(fmt::format("{}:{}: field {} ({}): expected a finite number, got '{}'", name,
                                   line, k + 1, names[k], printable(field)));
    out[k] = v;
  }
  return out;
}

void trajectory_io_append(Trajectory& t, double time, const Pose3& pose, std::size_t line) {
  if (!t.times.empty() && !(time > t.times.back()))
    throw ParseError(fmt::format("{}:{}: expected a time after {} (times must increase), got {}",
                                 t.source, line, t.times.back(), time));
  t.times.push_back(time);
  t.poses.push_back(pose);
}

void trajectory_io_require_poses(const Trajectory& t) {
  if (t.empty())
    throw ParseError(fmt::format("{}:1: expected at least one pose, got none", t.source));
}

}  // namespace

Trajectory parse_tum(std::string_view text, const std::string& name) {
  Trajectory t;
  t.source = name;
  trajectory_io_for_each_row(text, [&](std::size_t line, const auto& fields) {
    const auto v = trajectory_io_numbers(fields, kTrajectoryIoTumFields, name, line);
    Pose3 pose;
    pose.translation = Vec<3>(v[1], v[2], v[3]);
    pose.rotation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    const double norm = pose.rotation.norm();
    if (!(std::abs(norm - 1.0) <= kTrajectoryIoUnitTolerance))
      throw ParseError(fmt::format(
          "{}:{}: expected a unit quaternion (qx qy qz qw with norm within {} of 1), got norm {}",
          name, line, kTrajectoryIoUnitTolerance, norm));
    // A quaternion already unit to rounding is kept as written, so writing and reading a
    // trajectory gives the same doubles; normalising it would change its last bits.
    if (std::abs(norm - 1.0) > 4 * std::numeric_limits<double>::epsilon())
      pose.rotation.normalize();
    trajectory_io_append(t, v[0], pose, line);
  });
  trajectory_io_require_poses(t);
  return t;
}

Trajectory read_tum(const std::filesystem::path& path) {
  const std::filesystem::path resolved = resolve_data_file(path);
  return parse_tum(read_text_file(resolved), resolved.string());
}

std::string format_tum(const Trajectory& t) {
  std::string out = "# t x y z qx qy qz qw\n";
  for (std::size_t i = 0; i < t.size(); ++i) {
    const Pose3& p = t.poses[i];
    out += fmt::format("{} {} {} {} {} {} {} {}\n", t.times[i], p.translation(0), p.translation(1),
                       p.translation(2), p.rotation.x(), p.rotation.y(), p.rotation.z(),
                       p.rotation.w());
  }
  return out;
}

void write_tum(const std::filesystem::path& path, const Trajectory& trajectory) {
  trajectory.validate("write_tum");
  write_text_file(path, format_tum(trajectory));
}

Trajectory parse_kitti(std::string_view text, const std::string& name) {
  Trajectory t;
  t.source = name;
  trajectory_io_for_each_row(text, [&](std::size_t line, const auto& fields) {
    const auto v = trajectory_io_numbers(fields, kTrajectoryIoKittiFields, name, line);
    Eigen::Matrix3d r;
    r << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(off <= kTrajectoryIoUnitTolerance) || !(r.determinant() > 0))
      throw ParseError(fmt::format(
          "{}:{}: expected a rotation (R^T R = I within {}, det R = 1), got |R^T R - I| = {:.3g} "
          "and det R = {:.3g}",
          name, line, kTrajectoryIoUnitTolerance, off, r.determinant()));
    Pose3 pose;
    pose.translation = Vec<3>(v[3], v[7], v[11]);
    pose.rotation = Eigen::Quaterniond(r).normalized();
    trajectory_io_append(t, static_cast<double>(t.size()), pose, line);
  });
  trajectory_io_require_poses(t);
  return t;
}

Trajectory read_kitti(const std::filesystem::path& path) {
  const std::filesystem::path resolved = resolve_data_file(path);
  return parse_kitti(read_text_file(resolved), resolved.string());
}

std::vector<Relation> parse_relations(std::string_view text, const std::string& name) {
  std::vector<Relation> out;
  trajectory_io_for_each_row(text, [&](std::size_t line, const auto& fields) {
    const auto v = trajectory_io_numbers(fields, kTrajectoryIoRelationFields, name, line);
    if (v[0] == v[1])
      throw ParseError(
          fmt::format("{}:{}: expected two different times, got t1 = t2 = {}", name, line, v[0]));
    out.push_back({v[0], v[1], Pose3::from_rpy(Vec<3>(v[2], v[3], v[4]), v[5], v[6], v[7]), line});
  });
  if (out.empty())
    throw ParseError(fmt::format("{}:1: expected at least one relation, got none", name));
  return out;
}

std::vector<Relation> read_relations(const std::filesystem::path& path) {
  const std::filesystem::path resolved = resolve_data_file(path);
  return parse_relations(read_text_file(resolved), resolved.string());
}

}  // namespace implicit::robot
