#pragma once
// The inverse sensor model of occupancy grid mapping, one beam at a time: shared by the
// fixed-extent LogOddsGrid (grid_mapping.cpp) and the tiled, unbounded grid of grid SLAM
// (slam/grid/tiled_grid.cpp), so that the two agree cell by cell and cannot drift apart. Each map
// only says which cells exist (`inside`) and how a cell is stored (`update`).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "grid_walk.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot::detail {

/// How far beam i of a scan is used, and whether it ends in a hit (GridMappingOptions).
struct BeamUse {
  double length = 0.0;
  bool hit = false;
  bool used = false;
};

inline BeamUse beam_use(const LaserScan& scan, std::size_t i, double max_range) {
  const double r = scan.ranges[i];
  if (r < scan.range_min) return {};  // not a measurement
  const double limit = max_range > 0 ? max_range : scan.range_max;
  if (scan.is_hit(i) && r < limit) return {r, true, true};
  // No return within range_max says nothing beyond it, whatever max_range is.
  return {std::min(limit, scan.range_max), false, true};
}

/// A cell's log-odds after one observation: the sum kept in [-clamp, clamp], computed in double
/// and stored as float (every map stores floats: half the memory, and 1e-7 relative is far
/// below what an inverse sensor model means).
inline float add_log_odds(float old, double delta, double clamp) {
  return static_cast<float>(std::clamp(double(old) + delta, -clamp, clamp));
}

/// Whether a cell with `echoes` echoes is occupied whatever its log-odds
/// (GridMappingOptions::min_echoes; 0: never).
inline bool echoed(int echoes, const GridMappingOptions& options) {
  return options.min_echoes > 0 && echoes >= options.min_echoes;
}

/// Counts the echoes of one scan: `ends` holds the end cells of its hits (any order, repeats
/// allowed; sorted and deduplicated here), and each distinct cell's counter echo_of(cell) goes up
/// by one, saturating at 255. Once per scan: neighbouring beams of one scan often end in one
/// cell, and a single scan of a passer-by must not count twice.
template <class Cell, class EchoOf>
void count_scan_echoes(std::vector<Cell>& ends, EchoOf&& echo_of) {
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  for (const Cell& c : ends) {
    std::uint8_t& e = echo_of(c);
    if (e < 255) ++e;
  }
}

/// round(100 p) with p = 1 - 1 / (1 + exp(log-odds)): an observed cell's OccupancyGrid value.
inline std::int8_t occupancy_value(float log_odds) {
  const double p = 1.0 - 1.0 / (1.0 + std::exp(double(log_odds)));
  return static_cast<std::int8_t>(std::lround(100.0 * p));
}

inline void check_finite_mount(const LaserMount& mount, std::string_view who) {
  require(std::isfinite(mount.x) && std::isfinite(mount.y) && std::isfinite(mount.yaw),
          "{}: expected a finite laser mount, got ({}, {}, {})", who, mount.x, mount.y, mount.yaw);
}

/// The checks every integrate does before touching a cell (`who` names the caller).
inline void check_scan_input(const Pose& robot_pose, const LaserMount& mount, const LaserScan& scan,
                             std::string_view who) {
  scan.validate(who);
  require(robot_pose.allFinite(), "{}: expected a finite pose, got ({}, {}, {})", who,
          robot_pose(0), robot_pose(1), robot_pose(2));
  check_finite_mount(mount, who);
}

/// One beam in grid units: the ray g + t d (d a unit vector) walked from cell (ix, iy), which
/// holds its first point, up to t = end. Every cell it crosses is seen empty
/// (options.log_odds_miss); the cell of its end point is seen occupied (log_odds_hit) when `hit`,
/// empty otherwise. inside(ix, iy) says whether a cell exists: the walk stops at the first that
/// does not (the rest of the beam is outside the map). update(ix, iy, delta) adds delta to a cell.
template <class Inside, class Update>
void trace_beam(const Vec<2>& g, const Vec<2>& d, int ix, int iy, double end, bool hit,
                const GridMappingOptions& options, Inside&& inside, Update&& update) {
  CellWalk walk(g, d, ix, iy);
  for (;;) {
    const int px = walk.ix(), py = walk.iy();
    if (walk.next() >= end) {  // (px, py) holds the end point
      update(px, py, hit ? options.log_odds_hit : options.log_odds_miss);
      return;
    }
    update(px, py, options.log_odds_miss);
    if (!inside(walk.ix(), walk.iy())) return;
  }
}

}  // namespace implicit::robot::detail
