#include "implicit/robot/grid_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "grid_walk.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/scan_simulation.hpp"  // sensor_pose
#include "log_odds_beam.hpp"

namespace implicit::robot {
namespace {

constexpr double kMappingUnbounded = std::numeric_limits<double>::infinity();
}  // namespace

void GridMappingOptions::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  require(positive(resolution), "GridMappingOptions: expected resolution > 0 [m], got {}",
          resolution);
  require(positive(log_odds_hit), "GridMappingOptions: expected log_odds_hit > 0, got {}",
          log_odds_hit);
  require(std::isfinite(log_odds_miss) && log_odds_miss < 0,
          "GridMappingOptions: expected log_odds_miss < 0, got {}", log_odds_miss);
  require(positive(clamp), "GridMappingOptions: expected clamp > 0, got {}", clamp);
  require(std::isfinite(max_range) && max_range >= 0,
          "GridMappingOptions: expected max_range >= 0 [m] (0: the scan's range_max), got {}",
          max_range);
  require(std::isfinite(margin) && margin >= 0,
          "GridMappingOptions: expected margin >= 0 [m], got {}", margin);
  require(min_echoes >= 0 && min_echoes <= 255,
          "GridMappingOptions: expected min_echoes in [0, 255] (0: off), got {}", min_echoes);
}

LogOddsGrid::LogOddsGrid(int width, int height, double resolution, const Vec<2>& origin,
                         const GridMappingOptions& options)
    : width_(width), height_(height), resolution_(resolution), origin_(origin), options_(options) {
  options.validate();
  require(width > 0 && height > 0, "LogOddsGrid: expected a positive width and height, got {} x {}",
          width, height);
  require(std::isfinite(resolution) && resolution > 0,
          "LogOddsGrid: expected a positive, finite resolution [m], got {}", resolution);
  require(origin.allFinite(), "LogOddsGrid: expected a finite origin, got ({}, {})", origin.x(),
          origin.y());
  const auto cells = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  require(cells <= (std::uint64_t{1} << 31),
          "LogOddsGrid: expected at most 2^31 cells, got {} x {} = {}", width, height, cells);
  log_odds_.assign(static_cast<std::size_t>(cells), 0.0f);
  observed_.assign(static_cast<std::size_t>(cells), 0);
  echoes_.assign(static_cast<std::size_t>(cells), 0);
}

void LogOddsGrid::update(int ix, int iy, double delta) {
  const std::size_t k = index(ix, iy);
  log_odds_[k] = detail::add_log_odds(log_odds_[k], delta, options_.clamp);
  observed_[k] = 1;
}

// Walks the beam from `from` (world) along the unit vector `d` for `length` metres: misses in
// every cell it crosses, and in the cell of its end point a hit (or a miss when `hit` is false).
void LogOddsGrid::trace(const Vec<2>& from, const Vec<2>& d, double length, bool hit) {
  const double inv_res = 1.0 / resolution_;
  const Vec<2> g = (from - origin_) * inv_res;
  const double end = length * inv_res;
  double t = 0.0;
  if (!detail::enter_box(g, d, width_, height_, kMappingUnbounded, &t) || t > end) return;
  int ix = 0, iy = 0;
  detail::entry_cell(g + t * d, width_, height_, &ix, &iy);
  detail::trace_beam(
      g, d, ix, iy, end, hit, options_, [this](int x, int y) { return contains(x, y); },
      [this](int x, int y, double delta) { update(x, y, delta); });
}

void LogOddsGrid::integrate(const Pose& robot_pose, const LaserMount& mount,
                            const LaserScan& scan) {
  detail::check_scan_input(robot_pose, mount, scan, "LogOddsGrid::integrate");
  const Pose s = sensor_pose(robot_pose, mount);
  scan_ends_.clear();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const detail::BeamUse use = detail::beam_use(scan, i, options_.max_range);
    if (!use.used) continue;
    const double angle = s(2) + scan.bearing(i);
    const Vec<2> d(std::cos(angle), std::sin(angle));
    trace(s.head<2>(), d, use.length, use.hit);
    if (!use.hit) continue;
    const Vec<2> e = (s.head<2>() + use.length * d - origin_) / resolution_;
    const double fx = std::floor(e.x()), fy = std::floor(e.y());
    if (fx >= 0 && fy >= 0 && fx < width_ && fy < height_)
      scan_ends_.push_back(index(static_cast<int>(fx), static_cast<int>(fy)));
  }
  detail::count_scan_echoes(scan_ends_, [&](std::size_t k) -> std::uint8_t& {
    observed_[k] = 1;  // the trace's end cell; set here too in case rounding put them apart
    return echoes_[k];
  });
}

OccupancyGrid LogOddsGrid::to_occupancy() const {
  OccupancyGrid out(width_, height_, resolution_, origin_, OccupancyGrid::kUnknown);
  for (int iy = 0; iy < height_; ++iy)
    for (int ix = 0; ix < width_; ++ix) {
      if (!observed(ix, iy)) continue;
      const bool echoed = detail::echoed(echoes(ix, iy), options_);
      out.at(ix, iy) =
          echoed ? OccupancyGrid::kOccupied : detail::occupancy_value(log_odds(ix, iy));
    }
  return out;
}

OccupancyGrid build_map(std::span<const Pose> robot_poses, std::span<const LaserScan> scans,
                        const LaserMount& mount, const GridMappingOptions& options) {
  options.validate();
  require(robot_poses.size() == scans.size(),
          "build_map: expected one robot pose per scan, got {} poses and {} scans",
          robot_poses.size(), scans.size());
  require(!scans.empty(), "build_map: expected at least one scan, got none");
  detail::check_finite_mount(mount, "build_map");

  // The extent: every sensor position and every end point the mapper will reach.
  Vec<2> lo = Vec<2>::Constant(kMappingUnbounded), hi = -lo;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const Pose& x = robot_poses[k];
    require(x.allFinite(), "build_map: expected finite robot poses, got ({}, {}, {}) at pose {}",
            x(0), x(1), x(2), k);
    scans[k].validate(fmt::format("build_map: scan {}", k));
    const Pose s = sensor_pose(x, mount);
    lo = lo.cwiseMin(s.head<2>());
    hi = hi.cwiseMax(s.head<2>());
    for (std::size_t i = 0; i < scans[k].size(); ++i) {
      const detail::BeamUse use = detail::beam_use(scans[k], i, options.max_range);
      if (!use.used) continue;
      const double a = s(2) + scans[k].bearing(i);
      const Vec<2> e = s.head<2>() + use.length * Vec<2>(std::cos(a), std::sin(a));
      lo = lo.cwiseMin(e);
      hi = hi.cwiseMax(e);
    }
  }
  const double res = options.resolution;
  // The corner on a multiple of the resolution, so that maps of one place share their cells.
  const Vec<2> origin((std::floor((lo.x() - options.margin) / res)) * res,
                      (std::floor((lo.y() - options.margin) / res)) * res);
  const double w = std::floor((hi.x() + options.margin - origin.x()) / res) + 1;
  const double h = std::floor((hi.y() + options.margin - origin.y()) / res) + 1;
  // Compared as doubles, before any conversion to int (NaN fails too).
  if (!(w * h <= static_cast<double>(kMaxMappedCells)))
    throw InvalidArgument(fmt::format(
        "build_map: expected a map of at most {} cells, got {} x {} cells of {} m: x spans {} .. "
        "{} m and y spans {} .. {} m ({} m and {} m with the {} m margin; the larger is {}). "
        "Limit max_range or coarsen the resolution",
        kMaxMappedCells, w, h, res, lo.x(), hi.x(), lo.y(), hi.y(), w * res, h * res,
        options.margin, w >= h ? "x" : "y"));

  LogOddsGrid grid(static_cast<int>(w), static_cast<int>(h), res, origin, options);
  for (std::size_t k = 0; k < scans.size(); ++k) grid.integrate(robot_poses[k], mount, scans[k]);
  return grid.to_occupancy();
}

}  // namespace implicit::robot
