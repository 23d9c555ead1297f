// The laser dataset: a CARMEN log's scans and reference poses at nav2-style update points, the
// map (built from the reference poses or read), and the synthesised odometry (the semi-synthetic
// protocol); or a robot log's scans with its recorded odometry, its map and, where it has them,
// its truth records as the reference.
#include <algorithm>
#include <cmath>

#include "experiments/laser_mcl.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/log_format.hpp"
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
  require(map_min_echoes >= 0 && map_min_echoes <= 255,
          "laser data: expected map_min_echoes in [0, 255] (0: off), got {}", map_min_echoes);
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

/// A reference pose outside the map is a map that does not belong to the log (updates without a
/// reference, NaN, are not checked).
void require_reference_on_map(const LaserDataset& d, const std::string& where) {
  for (std::size_t k = 0; k < d.reference.size(); ++k) {
    if (!d.reference[k].head<2>().allFinite()) continue;
    const Eigen::Vector2i c = d.map.cell_of(d.reference[k].head<2>());
    require(d.map.contains(c(0), c(1)),
            "{}: the reference pose of update {} ({:.2f}, {:.2f}) is outside the map ({} x {} "
            "cells from ({:.2f}, {:.2f})): is it the map of this log?",
            where, k, d.reference[k](0), d.reference[k](1), d.map.width(), d.map.height(),
            d.map.origin()(0), d.map.origin()(1));
  }
}

void require_updates(const LaserDataset& d, const LaserDataOptions& options) {
  require(d.scans.size() >= 2,
          "{}: expected at least 2 updates (the {} must move update_min_d = {} m or turn "
          "update_min_a = {} rad), got {}",
          options.data.string(), d.odometry_recorded() ? "odometry" : "reference",
          options.update_min_d, options.update_min_a, d.scans.size());
}

/// The map of a robot log: --map if given, else the file of the log's `map` record.
robot::OccupancyGrid map_of(const LaserDataOptions& options, const robot::RobotLog& log) {
  if (!options.map.empty()) return robot::load_map(options.map);
  require(log.map.has_value(),
          "{}: expected a map to match the scans against: --map FILE, or a 'map' record in the "
          "log; got neither",
          log.source);
  try {
    return robot::load_map(robot::map_file(log));
  } catch (const ParseError& e) {  // the map reader names the map, not the record that named it
    throw ParseError(fmt::format("{}:{}: 'map' record: {}", log.source, log.map->line, e.what()));
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(
        fmt::format("{}:{}: 'map' record: {}", log.source, log.map->line, e.what()));
  }
}

/// A robot log with `laser` and `odometry` records: each scan gets the odometry pose interpolated
/// at its time (scans outside the odometry's time span have no control and are left out) and the
/// truth interpolated there (NaN where there is none: not scored); updates are picked on the
/// odometry, as nav2 does.
LaserDataset load_robot_log(const LaserDataOptions& options) {
  const robot::RobotLog log = robot::read_robot_log(options.data);
  require(!log.laser_scans.empty(), "{}: expected 'laser' records (the scans), got none",
          log.source);
  require(!log.odometry.empty(),
          "{}: expected 'odometry' records (the control of a laser run), got none", log.source);
  LaserDataset d;
  d.name = options.data.filename().string();
  d.scans_in_log = log.laser_scans.size();
  if (log.laser_mount) d.mount = *log.laser_mount;
  d.map = map_of(options, log);
  std::vector<double> times;
  for (const robot::LaserScan& s : log.laser_scans) times.push_back(s.time);
  const std::vector<robot::Pose> odometry = robot::interpolate_odometry(log, times);
  const robot::TruthTrack truth = robot::interpolate_truth(log, times);
  std::vector<std::size_t> covered;  // scans with odometry
  std::vector<robot::Pose> covered_odometry;
  for (std::size_t i = 0; i < times.size(); ++i)
    if (odometry[i].allFinite()) {
      covered.push_back(i);
      covered_odometry.push_back(odometry[i]);
    }
  require(!covered.empty(),
          "{}: expected 'laser' records within the time span of the 'odometry' records ({} to {} "
          "s), got none there (the scans from {} to {} s)",
          log.source, log.odometry.front().time, log.odometry.back().time, times.front(),
          times.back());
  for (std::size_t k : update_points(covered_odometry, options)) {
    const std::size_t i = covered[k];
    d.scans.push_back(log.laser_scans[i]);
    d.odometry.push_back(odometry[i]);
    d.reference.emplace_back(truth.position[i](0), truth.position[i](1), truth.heading[i]);
  }
  require_updates(d, options);
  require_reference_on_map(d, options.data.string());
  return d;
}

/// A CARMEN log by the semi-synthetic protocol: the recorded laser poses are the reference.
LaserDataset load_carmen(const LaserDataOptions& options, const robot::CarmenLog& log) {
  require(!log.scans.empty(), "{}: expected laser scans, got none", options.data.string());
  LaserDataset d;
  // A rosbag2 folder may be named with a trailing '/': its name is then the folder's.
  const std::filesystem::path data = options.data.lexically_normal();
  d.name = (data.has_filename() ? data : data.parent_path()).filename().string();
  d.scans_in_log = log.scans.size();
  d.mount = mount_of(log);
  const robot::Pose mount_pose(d.mount.x, d.mount.y, d.mount.yaw);
  // The robot's reference pose: the recorded laser pose with the mount taken off.
  std::vector<robot::Pose> robot_poses(log.scans.size());
  for (std::size_t i = 0; i < log.scans.size(); ++i)
    robot_poses[i] =
        robot::compose(log.laser_poses[i], robot::between(mount_pose, robot::Pose::Zero()));
  if (options.map.empty()) {
    robot::GridMappingOptions m;
    m.resolution = options.map_resolution;
    m.max_range = options.map_max_range;
    m.min_echoes = options.map_min_echoes;
    d.map = robot::build_map(robot_poses, log.scans, d.mount, m);
    d.map_built = true;
  } else {
    d.map = robot::load_map(options.map);
  }
  for (std::size_t i : update_points(robot_poses, options)) {
    d.scans.push_back(log.scans[i]);
    d.reference.push_back(robot_poses[i]);
  }
  require_updates(d, options);
  require_reference_on_map(d, options.data.string());
  return d;
}

}  // namespace

LaserDataset load_laser_dataset(const LaserDataOptions& options) {
  options.validate();
  if (robot::is_bag(options.data))
    return load_carmen(options, robot::read_bag_laser_log(options.data, options.bag).log);
  // The format from the content (any name, gzip or not): a robot log's first record is one of
  // its lower-case kinds, a CARMEN log's an upper-case message name.
  const std::string text = robot::read_text_file(options.data);
  if (robot::is_robot_log(text)) return load_robot_log(options);
  return load_carmen(options,
                     robot::parse_carmen(text, robot::resolve_data_file(options.data).string()));
}

std::vector<Vec<3>> run_odometry(const LaserDataset& d, const robot::OdometryAlphas& noise,
                                 std::uint64_t seed) {
  if (!d.odometry_recorded()) return synthesise_odometry(d.reference, noise, seed);
  std::vector<Vec<3>> u(d.odometry.size(), Vec<3>::Zero());
  for (std::size_t k = 1; k < u.size(); ++k) {
    u[k] = robot::between(d.odometry[k - 1], d.odometry[k]);
    // Headings recorded within (-pi, pi] jump by 2 pi across pi; no robot turns half a circle
    // between two updates.
    u[k](2) = wrap_angle(u[k](2));
  }
  return u;
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
