#include "implicit/robot/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "grid_walk.hpp"
#include "implicit/core/error.hpp"

namespace implicit::robot {

OccupancyGrid::OccupancyGrid(int width, int height, double resolution, const Vec<2>& origin,
                             std::int8_t fill)
    : width_(width), height_(height), resolution_(resolution), origin_(origin) {
  require(width > 0 && height > 0,
          "OccupancyGrid: expected a positive width and height, got {} x {}", width, height);
  require(std::isfinite(resolution) && resolution > 0,
          "OccupancyGrid: expected a positive, finite resolution [m], got {}", resolution);
  require(origin.allFinite(), "OccupancyGrid: expected a finite origin, got ({}, {})", origin.x(),
          origin.y());
  require(fill >= kUnknown && fill <= kOccupied,
          "OccupancyGrid: expected a fill value in -1..100, got {}", static_cast<int>(fill));
  const auto cells = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  require(cells <= (std::uint64_t{1} << 31),
          "OccupancyGrid: expected at most 2^31 cells, got {} x {} = {}", width, height, cells);
  cells_.assign(static_cast<std::size_t>(cells), fill);
}

Eigen::Vector2i OccupancyGrid::cell_of(const Vec<2>& p) const {
  require(!std::isnan(p.x()) && !std::isnan(p.y()),
          "OccupancyGrid::cell_of: expected a point, got ({}, {})", p.x(), p.y());
  // Clamped to the range of int before the conversion (converting a larger double is
  // undefined); points that far away are outside any grid either way.
  constexpr double kLo = -2147483648.0, kHi = 2147483647.0;
  const double gx = std::floor((p.x() - origin_.x()) / resolution_);
  const double gy = std::floor((p.y() - origin_.y()) / resolution_);
  return Eigen::Vector2i(static_cast<int>(std::clamp(gx, kLo, kHi)),
                         static_cast<int>(std::clamp(gy, kLo, kHi)));
}

Vec<2> OccupancyGrid::cell_center(int ix, int iy) const {
  return Vec<2>(origin_.x() + (ix + 0.5) * resolution_, origin_.y() + (iy + 0.5) * resolution_);
}

double cast_ray(const OccupancyGrid& grid, const Vec<2>& from, double angle, double max_range) {
  require(!grid.empty(), "cast_ray: expected a grid with cells, got an empty one");
  require(from.allFinite() && std::isfinite(angle),
          "cast_ray: expected a finite start and angle, got ({}, {}) and {}", from.x(), from.y(),
          angle);
  require(std::isfinite(max_range) && max_range >= 0,
          "cast_ray: expected a finite max_range >= 0, got {}", max_range);
  const double inv_res = 1.0 / grid.resolution();
  const Vec<2> g = (from - grid.origin()) * inv_res;
  const Vec<2> d(std::cos(angle), std::sin(angle));
  const double t_max = max_range * inv_res;
  // A start outside the grid is fine: the ray may still cross it (outside counts as empty).
  double t = 0.0;
  if (!detail::enter_box(g, d, grid.width(), grid.height(), t_max, &t)) return max_range;
  int ix = 0, iy = 0;
  detail::entry_cell(g + t * d, grid.width(), grid.height(), &ix, &iy);
  detail::CellWalk walk(g, d, ix, iy);
  // The range to the first occupied cell is the t at which the ray enters it.
  const auto hit_at = [&](double t_hit) { return std::min(t_hit * grid.resolution(), max_range); };
  if (grid.is_occupied(ix, iy)) return hit_at(t);
  for (;;) {
    const int px = walk.ix(), py = walk.iy();
    t = walk.next();
    if (t >= t_max) return max_range;
    // Through a corner exactly: the ray touches the two cells beside it. Either one occupied
    // stops it, so that a wall drawn as a diagonal staircase of cells is not see-through.
    if (walk.diagonal() && ((grid.contains(walk.ix(), py) && grid.is_occupied(walk.ix(), py)) ||
                            (grid.contains(px, walk.iy()) && grid.is_occupied(px, walk.iy()))))
      return hit_at(t);
    if (!grid.contains(walk.ix(), walk.iy())) return max_range;
    if (grid.is_occupied(walk.ix(), walk.iy())) return hit_at(t);
  }
}

}  // namespace implicit::robot
