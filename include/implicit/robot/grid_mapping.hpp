#pragma once
// Occupancy grid mapping with known poses: the map a localization run needs, built from laser
// scans taken where the robot is known to have been (Thrun, Burgard and Fox, Probabilistic
// Robotics, ch. 9: log-odds updates with an inverse sensor model).
//
// Each beam is walked through the grid from the sensor: the cells it crosses were seen empty
// (log_odds_miss), the cell of its end point was seen occupied (log_odds_hit). A beam with no
// return (at or beyond range_max, or beyond the options' max_range) only clears cells up to
// that range; a reading below range_min is ignored. Log-odds are clamped to +-clamp, so that a
// cell seen often can still change when the world does.
//
// Echoes: a cell in which beams of at least min_echoes scans ended is occupied in the map,
// whatever its log-odds. Log-odds alone erase thin walls: a beam that grazes a wall at a few
// degrees crosses the wall's cells for tens of centimetres before its own end point, and a log
// of hundreds of scans grazes every corridor wall far more often than it hits it, so walls seen
// edge-on fade (and a stretch where a wall was seen only for a while loses it). A localization
// map is read through its obstacles (the likelihood field scores where beams end, never what
// they cross), so a place that returned echoes in several scans belongs in it; two scans keep a
// single spurious return out. On the bundled Intel and Freiburg 079 logs this is the difference
// between a tracking filter that loses runs and one that loses none (docs/performance.md).
//
//   std::vector<Pose> poses = ...;             // one per scan, the robot's, in the world
//   std::vector<LaserScan> scans = ...;
//   OccupancyGrid map = build_map(poses, scans, LaserMount{0.1, 0.0, 0.0}, {});
//   save_map(map, "built.yaml");               // map_io.hpp

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

struct GridMappingOptions {
  double resolution = 0.05;     ///< [m] cell size (build_map)
  double log_odds_hit = 0.85;   ///< added to the end cell of a beam (about p = 0.7)
  double log_odds_miss = -0.4;  ///< added to the cells a beam crosses (about p = 0.4)
  double clamp = 5.0;           ///< log-odds are kept in [-clamp, clamp]
  /// A cell where beams of at least this many scans ended is occupied (100) in to_occupancy,
  /// whatever its log-odds; 0 leaves the log-odds alone. In [0, 255]. The tiled grid of grid
  /// SLAM counts them the same way (GridSlamOptions sets 1).
  int min_echoes = 2;
  /// [m] beams are used up to this range; 0 means each scan's range_max. A reading at or
  /// beyond it clears the cells up to it (up to range_max at most) and marks no hit.
  double max_range = 0.0;
  double margin = 1.0;  ///< [m] unknown cells around the data (build_map)

  /// Throws InvalidArgument naming the first option out of range (resolution, clamp and
  /// log_odds_hit positive, log_odds_miss negative, max_range and margin >= 0, all finite;
  /// min_echoes in [0, 255]).
  void validate() const;
};

/// Log-odds of occupancy over a fixed extent, one float per cell.
class LogOddsGrid {
 public:
  /// width x height cells like OccupancyGrid's; throws InvalidArgument as its constructor does,
  /// or for invalid options (options.resolution is not used: `resolution` is).
  LogOddsGrid(int width, int height, double resolution, const Vec<2>& origin,
              const GridMappingOptions& options = {});

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Vec<2>& origin() const { return origin_; }

  /// Adds one scan taken at robot_pose. Parts of beams outside the extent are skipped. Throws
  /// InvalidArgument for a scan that fails LaserScan::validate or a non-finite pose or mount.
  void integrate(const Pose& robot_pose, const LaserMount& mount, const LaserScan& scan);

  /// Cell (ix, iy)'s log-odds (0 for a cell never observed); contains(ix, iy) must hold.
  float log_odds(int ix, int iy) const { return log_odds_[index(ix, iy)]; }
  bool observed(int ix, int iy) const { return observed_[index(ix, iy)] != 0; }
  /// How many scans had a beam end in cell (ix, iy) (saturating at 255).
  int echoes(int ix, int iy) const { return echoes_[index(ix, iy)]; }
  bool contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }

  /// round(100 p) with p = 1 - 1 / (1 + exp(log-odds)); cells never observed are -1; cells with
  /// at least options.min_echoes echoes (when it is positive) are 100.
  OccupancyGrid to_occupancy() const;

 private:
  std::size_t index(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(ix);
  }
  void update(int ix, int iy, double delta);
  void trace(const Vec<2>& from, const Vec<2>& direction, double length, bool hit);

  int width_ = 0, height_ = 0;
  double resolution_ = 0.0;
  Vec<2> origin_ = Vec<2>::Zero();
  GridMappingOptions options_;
  std::vector<float> log_odds_;
  std::vector<std::uint8_t> observed_;
  std::vector<std::uint8_t> echoes_;
  std::vector<std::size_t> scan_ends_;  ///< integrate's scratch: the cells one scan's beams end in
};

/// The cells larger maps than this are refused by build_map (2^26: 64 Mi cells).
inline constexpr std::int64_t kMaxMappedCells = std::int64_t{1} << 26;

/// A map from scans at known robot poses (one pose per scan): the extent covers every sensor
/// position and beam end point plus options.margin, with its corner on a multiple of the
/// resolution (maps of the same place line up). Throws InvalidArgument for different counts of
/// poses and scans, no scan, a non-finite pose (naming its index), a scan that fails
/// LaserScan::validate ("scan k"), invalid options, or an extent of more than kMaxMappedCells
/// cells (naming the extent in x and y).
OccupancyGrid build_map(std::span<const Pose> robot_poses, std::span<const LaserScan> scans,
                        const LaserMount& mount, const GridMappingOptions& options);

}  // namespace implicit::robot
