#pragma once
// Occupancy grids: the map that laser localization matches scans against.
//
// Cell values follow ROS nav_msgs/OccupancyGrid: 0 (free) .. 100 (occupied), -1 unknown. Cell
// (ix, iy) covers [origin.x + ix * resolution, origin.x + (ix + 1) * resolution) and likewise
// in y; row iy = 0 is the lowest y (a PGM image stores the highest y first: map_io flips it).
//
//   OccupancyGrid grid(400, 300, 0.05, Vec<2>(-10.0, -7.5));   // 20 m x 15 m, all unknown
//   grid.at(12, 40) = OccupancyGrid::kOccupied;
//   Eigen::Vector2i c = grid.cell_of(Vec<2>(1.0, 2.0));          // may be outside the grid
//
// A cell counts as occupied at value >= kOccupiedAt (65, map_server's default occupied_thresh
// of 0.65) and as free at 0 <= value <= kFreeAt (19, free_thresh 0.196); a map loaded in
// trinary mode holds only 0, 100 and -1.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit::robot {

class OccupancyGrid {
 public:
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;
  static constexpr std::int8_t kOccupiedAt = 65;
  static constexpr std::int8_t kFreeAt = 19;

  OccupancyGrid() = default;
  /// width x height cells of `resolution` metres, cell (0, 0)'s lower-left corner at `origin`,
  /// every cell `fill`. Throws InvalidArgument for non-positive sizes or resolution, a
  /// non-finite origin, a fill outside -1..100, or more than 2^31 cells.
  OccupancyGrid(int width, int height, double resolution, const Vec<2>& origin,
                std::int8_t fill = kUnknown);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Vec<2>& origin() const { return origin_; }
  bool empty() const { return cells_.empty(); }

  bool contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }
  /// Unchecked access (contains(ix, iy) must hold).
  std::int8_t at(int ix, int iy) const { return cells_[index(ix, iy)]; }
  std::int8_t& at(int ix, int iy) { return cells_[index(ix, iy)]; }
  bool is_occupied(int ix, int iy) const { return at(ix, iy) >= kOccupiedAt; }
  bool is_free(int ix, int iy) const {
    const std::int8_t v = at(ix, iy);
    return v >= 0 && v <= kFreeAt;
  }

  /// The cell that contains world point p (floor of the grid coordinates; may be outside).
  Eigen::Vector2i cell_of(const Vec<2>& p) const;
  /// The world coordinates of the centre of cell (ix, iy).
  Vec<2> cell_center(int ix, int iy) const;

  /// Row-major cells, row 0 the lowest y.
  std::span<const std::int8_t> data() const { return cells_; }
  std::span<std::int8_t> data() { return cells_; }

 private:
  std::size_t index(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(ix);
  }
  int width_ = 0, height_ = 0;
  double resolution_ = 0.0;
  Vec<2> origin_ = Vec<2>::Zero();
  std::vector<std::int8_t> cells_;
};

/// The range from `from` along heading `angle` to the first occupied cell, walking the cells the
/// ray crosses (Amanatides-Woo), up to max_range; max_range when nothing is hit within it or
/// the ray leaves the grid. A start inside an occupied cell gives 0. A start outside the grid is
/// allowed: the ray is followed from where it enters (cells outside count as empty). A ray
/// through a cell corner exactly stops there if either cell beside the corner is occupied, so
/// that a diagonal wall of cells touching at corners is not see-through. Throws InvalidArgument
/// for an empty grid, a non-finite start or angle, or a max_range that is negative or infinite.
double cast_ray(const OccupancyGrid& grid, const Vec<2>& from, double angle, double max_range);

}  // namespace implicit::robot
