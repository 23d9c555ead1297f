#pragma once
// Walking the cells a ray crosses, in order (Amanatides and Woo, "A fast voxel traversal
// algorithm", 1987): shared by cast_ray (occupancy_grid.cpp) and the mapper (grid_mapping.cpp).
//
// Everything is in grid units: cell (i, j) covers [i, i + 1) x [j, j + 1), the ray is g + t d
// with d a unit vector, so t is the distance travelled in cells (times the resolution: metres).

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/types.hpp"

namespace implicit::robot::detail {

class CellWalk {
 public:
  /// The walk of ray g + t d starting in cell (ix, iy), which must contain (or touch) the ray's
  /// first point of interest; d must be a unit vector.
  CellWalk(const Vec<2>& g, const Vec<2>& d, int ix, int iy)
      : gx_(g.x()), gy_(g.y()), ix_(ix), iy_(iy) {
    step_x_ = d.x() > 0 ? 1 : (d.x() < 0 ? -1 : 0);
    step_y_ = d.y() > 0 ? 1 : (d.y() < 0 ? -1 : 0);
    // Zero components never reach a boundary; 1/d is never formed for them.
    inv_x_ = step_x_ != 0 ? 1.0 / d.x() : 0.0;
    inv_y_ = step_y_ != 0 ? 1.0 / d.y() : 0.0;
  }

  int ix() const { return ix_; }
  int iy() const { return iy_; }
  /// Whether the last next() went through a corner (both indices changed at once): the ray
  /// then only touched the two cells beside the corner.
  bool diagonal() const { return diagonal_; }

  /// Moves to the next cell and returns the t at which the ray enters it. The boundary times
  /// are recomputed from g each step (not accumulated), so long rays do not drift.
  double next() {
    constexpr double kNever = std::numeric_limits<double>::infinity();
    const double tx = step_x_ != 0 ? (ix_ + (step_x_ > 0 ? 1 : 0) - gx_) * inv_x_ : kNever;
    const double ty = step_y_ != 0 ? (iy_ + (step_y_ > 0 ? 1 : 0) - gy_) * inv_y_ : kNever;
    diagonal_ = tx == ty;
    if (tx <= ty) ix_ += step_x_;
    if (ty <= tx) iy_ += step_y_;
    return tx < ty ? tx : ty;
  }

 private:
  double gx_, gy_;
  int ix_, iy_;
  int step_x_ = 0, step_y_ = 0;
  double inv_x_ = 0.0, inv_y_ = 0.0;
  bool diagonal_ = false;
};

/// Where ray g + t d (t >= 0, d a unit vector) first meets the box [0, w] x [0, h]: t = 0 when
/// g is inside; false when the ray misses the box or meets it only at t >= t_max.
inline bool enter_box(const Vec<2>& g, const Vec<2>& d, double w, double h, double t_max,
                      double* t_enter) {
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  const double size[2] = {w, h};
  for (int k = 0; k < 2; ++k) {
    if (d(k) == 0) {
      if (!(g(k) >= 0 && g(k) < size[k])) return false;
      continue;
    }
    const double a = (0.0 - g(k)) / d(k), b = (size[k] - g(k)) / d(k);
    lo = std::max(lo, std::min(a, b));
    hi = std::min(hi, std::max(a, b));
  }
  *t_enter = lo;
  return lo < hi && lo < t_max;
}

/// The cell of a w x h grid where a ray that entered the box at point e starts (e on the
/// boundary floors to w or h on the far sides: those belong to the last cell).
inline void entry_cell(const Vec<2>& e, int w, int h, int* ix, int* iy) {
  *ix = std::clamp(static_cast<int>(std::floor(std::clamp(e.x(), 0.0, double(w)))), 0, w - 1);
  *iy = std::clamp(static_cast<int>(std::floor(std::clamp(e.y(), 0.0, double(h)))), 0, h - 1);
}

}  // namespace implicit::robot::detail
