#pragma once
// The distance from any point of the plane to the nearest occupied cell of a grid: what the
// likelihood-field laser model (likelihood_field.hpp) evaluates at every beam end point.
//
//   DistanceField field(grid, 2.0);                        // nav2's laser_likelihood_max_dist
//   double d = field.cell_distance(ix, iy);                // exact, at cell centres
//   Vec<2> g;
//   double s = field.distance(p, Interpolation::kBicubic, &g);   // smooth, with its gradient
//
// Construction runs the exact Euclidean distance transform of Felzenszwalb and Huttenlocher
// (2012), linear in the number of cells: two passes of the lower envelope of parabolas, over
// columns and then over rows. Distances are between cell centres, in metres, and capped at
// max_distance (also where the grid has no occupied cell at all). Outside the grid the field
// goes on as the distance to the grid's occupied cells (the transform runs on the grid padded
// by max_distance of free cells), so it is continuous across the border.
//
// Interpolation between cell centres:
//   kNearest   the value of the cell containing p; gradient zero (the AMCL/Beluga lookup);
//   kBilinear  continuous, gradient piecewise constant;
//   kBicubic   Catmull-Rom (Keys, a = -1/2): C1, so Newton's method sees a continuous gradient.
// Every mode reproduces cell_distance() at cell centres (to rounding: the centre's grid
// coordinate is computed in floating point). Bicubic values may overshoot the cell values
// slightly between cells, as Catmull-Rom does; they are not clamped, which would break C1.
// A NaN point gives NaN (and a NaN gradient): a caller's weight of zero, not an exception in a
// per-particle loop.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::robot {
namespace detail {
struct FieldLookup;
}

enum class Interpolation { kNearest, kBilinear, kBicubic };

class DistanceField {
 public:
  DistanceField() = default;
  /// Throws InvalidArgument for an empty grid or a max_distance that is not positive and finite.
  DistanceField(const OccupancyGrid& grid, double max_distance);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Vec<2>& origin() const { return origin_; }
  /// The cap, as given rounded to float (the precision every distance is stored in).
  double max_distance() const { return max_distance_; }

  /// The capped distance at the centre of cell (ix, iy), also outside the grid.
  double cell_distance(int ix, int iy) const;
  /// The interpolated distance at world point p and, if gradient is not null, its gradient
  /// d distance / d p (zero for kNearest).
  double distance(const Vec<2>& p, Interpolation mode, Vec<2>* gradient = nullptr) const;

 private:
  // The likelihood field evaluates whole scans with the lookups of lookup() inlined into its
  // loops (likelihood_field.cpp), and tabulates its beam density over the cells.
  friend class LikelihoodFieldModel;

  int width_ = 0, height_ = 0;
  double resolution_ = 0.0;
  Vec<2> origin_ = Vec<2>::Zero();
  double max_distance_ = 0.0;
  int pad_ = 2;  ///< free cells around the grid in the transform (>= max_distance + 3 cells)
  std::vector<float> padded_;  ///< (width + 2 pad) x (height + 2 pad), row-major, row 0 lowest y
  int padded_width_ = 0;
  double inv_resolution_ = 0.0;  ///< cells per metre: distance() multiplies, never divides
  /// Grid coordinates (in cells) inside which distance() interpolates; farther out every mode
  /// reads only max_distance. Empty for a default-constructed field.
  double u_lo_ = 0.0, u_hi_ = 0.0, v_lo_ = 0.0, v_hi_ = 0.0;

  /// The stored distance of cell (ix, iy), max_distance beyond the padding.
  float value_at(int ix, int iy) const {
    const int px = ix + pad_, py = iy + pad_;
    if (px < 0 || py < 0 || px >= padded_width_ || py >= height_ + 2 * pad_)
      return static_cast<float>(max_distance_);
    return padded_[static_cast<std::size_t>(py) * static_cast<std::size_t>(padded_width_) +
                   static_cast<std::size_t>(px)];
  }
  /// The cells and constants for the per-point lookups (distance_field_kernels.hpp in src/).
  detail::FieldLookup lookup() const;
  double outside(double u, double v, Vec<2>* gradient) const;
};

/// Squared Euclidean distances, in cells, from each cell to the nearest cell with
/// occupied[k] != 0 (Felzenszwalb-Huttenlocher); cells of a grid without any occupied cell get
/// +infinity. Row-major, width x height. Exposed for tests against brute force.
std::vector<double> squared_distance_transform(std::span<const std::uint8_t> occupied, int width,
                                               int height);

}  // namespace implicit::robot
