// The semi-synthetic laser dataset: a CARMEN log's scans and reference poses at nav2-style update
// points, the map (built from the reference poses or read), and the synthesised odometry.
#include <algorithm>
#include <cmath>

#include "experiments/laser_mcl.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/map_io.hpp"

namespace implicit::experiments {

std::string_view to_string(ProposalKind p) {
  return p == ProposalKind::kBootstrap ? "bootstrap" : "implicit";
}

ProposalKind parse_proposal(std::string_view text) {
  if (text == "bootstrap" || text == "standard") return ProposalKind::kBootstrap;
  if (text == "implicit") return ProposalKind::kImplicit;
  throw InvalidArgument(
      fmt::format("expected a proposal 'bootstrap' or 'implicit', got '{}'", printable(text)));
}

std::string_view to_string(StartKind s) { return s == StartKind::kKnown ? "known" : "global"; }

StartKind parse_start(std::string_view text) {
  if (text == "known") return StartKind::kKnown;
  if (text == "global") return StartKind::kGlobal;
  throw InvalidArgument(
      fmt::format("expected a start 'known' or 'global', got '{}'", printable(text)));
}

robot::Interpolation parse_interpolation(std::string_view text) {
  if (text == "nearest") return robot::Interpolation::kNearest;
  if (text == "bilinear") return robot::Interpolation::kBilinear;
  if (text == "bicubic") return robot::Interpolation::kBicubic;
  throw InvalidArgument(fmt::format(
      "expected an interpolation 'nearest', 'bilinear' or 'bicubic', got '{}'", printable(text)));
}

std::string_view to_string(robot::Interpolation i) {
  switch (i) {
    case robot::Interpolation::kNearest:
      return "nearest";
    case robot::Interpolation::kBilinear:
      return "bilinear";
    case robot::Interpolation::kBicubic:
      return "bicubic";
  }
  return "unknown";
}

void LaserDataOptions::validate() const {
  require(!data.empty(), "laser data: expected a log file (--data), got none");
  require(map_resolution >= 0.005 && map_resolution <= 1.0,
          "laser data: expected a map resolution in [0.005, 1] m, got {}", map_resolution);
  require(map_max_range > 0 && std::isfinite(map_max_range),
          "laser data: expected a positive mapping range, got {}", map_max_range);
  require(update_min_d >= 0 && std::isfinite(update_min_d),
          "laser data: expected update_min_d >= 0 [m], got {}", update_min_d);
  require(update_min_a >= 0 && std::isfinite(update_min_a),
          "laser data: expected update_min_a >= 0 [rad], got {}", update_min_a);
}

namespace {

/// The laser's pose on the robot: the recorded laser pose seen from the recorded robot pose
/// (constant in a log; zero where the log records the laser's pose for both).
robot::LaserMount mount_of(const robot::CarmenLog& log) {
  const robot::Pose d = robot::between(log.odometry_poses.front(), log.laser_poses.front());
  return {d(0), d(1), wrap_angle(d(2))};
}

/// The scans at which nav2 would update: the first, then each one whose reference pose moved
/// update_min_d or turned update_min_a since the last update.
std::vector<std::size_t> update_points(const std::vector<robot::Pose>& poses,
                                       const LaserDataOptions& o) {
  std::vector<std::size_t> picked;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!picked.empty()) {
      const robot::Pose& last = poses[picked.back()];
      const double moved = (poses[i].head<2>() - last.head<2>()).norm();
      const double turned = std::abs(wrap_angle(poses[i](2) - last(2)));
      if (moved < o.update_min_d && turned < o.update_min_a) continue;
    }
    picked.push_back(i);
    if (o.max_updates > 0 && picked.size() >= o.max_updates) break;
  }
  return picked;
}

}  // namespace

LaserDataset load_laser_dataset(const LaserDataOptions& options) {
  options.validate();
  const robot::CarmenLog log = robot::read_carmen(options.data);
  require(!log.scans.empty(), "{}: expected laser scans, got none", options.data.string());
  LaserDataset d;
  d.name = options.data.filename().string();
  d.scans_in_log = log.scans.size();
  d.mount = mount_of(log);
  const robot::Pose mount_pose(d.mount.x, d.mount.y, d.mount.yaw);
  // The robot's reference pose: the recorded laser pose with the mount taken off.
  std::vector<robot::Pose> robot_poses(log.scans.size());
  for (std::size_t i = 0; i < log.scans.size(); ++i)
    robot_poses[i] = robot::compose(log.laser_poses[i],
                                    robot::between(mount_pose, robot::Pose::Zero()));
  if (options.map.empty()) {
    robot::GridMappingOptions m;
    m.resolution = options.map_resolution;
    m.max_range = options.map_max_range;
    d.map = robot::build_map(robot_poses, log.scans, d.mount, m);
    d.map_built = true;
  } else {
    d.map = robot::load_map(options.map);
  }
  for (std::size_t i : update_points(robot_poses, options)) {
    d.scans.push_back(log.scans[i]);
    d.reference.push_back(robot_poses[i]);
  }
  require(d.scans.size() >= 2,
          "{}: expected at least 2 updates (the reference must move update_min_d = {} m or turn "
          "update_min_a = {} rad), got {}",
          options.data.string(), options.update_min_d, options.update_min_a, d.scans.size());
  // A reference pose outside the map is a map that does not belong to the log.
  for (std::size_t k = 0; k < d.reference.size(); ++k) {
    const Eigen::Vector2i c = d.map.cell_of(d.reference[k].head<2>());
    require(d.map.contains(c(0), c(1)),
            "{}: the reference pose of update {} ({:.2f}, {:.2f}) is outside the map ({} x {} "
            "cells from ({:.2f}, {:.2f})): is it the map of this log?",
            options.data.string(), k, d.reference[k](0), d.reference[k](1), d.map.width(),
            d.map.height(), d.map.origin()(0), d.map.origin()(1));
  }
  return d;
}

std::vector<Vec<3>> synthesise_odometry(const std::vector<robot::Pose>& reference,
                                        const robot::OdometryAlphas& alphas, std::uint64_t seed) {
  std::vector<Vec<3>> u(reference.size(), Vec<3>::Zero());
  for (std::size_t k = 1; k < reference.size(); ++k) {
    Rng rng({seed, k, 0, purpose::kData});
    u[k] = robot::perturb_odometry(robot::between(reference[k - 1], reference[k]), alphas, rng);
  }
  return u;
}

}  // namespace implicit::experiments
