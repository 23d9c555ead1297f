#include "implicit/robot/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "distance_field_kernels.hpp"
#include "implicit/core/error.hpp"

namespace implicit::robot {
namespace {

constexpr double kEnvelopeInf = std::numeric_limits<double>::infinity();

// The lower envelope of the parabolas (x - q)^2 + f[q] over the finite samples f[q], evaluated
// at x = 0 .. n-1 into d (Felzenszwalb and Huttenlocher 2012, one-dimensional DT). Infinite
// samples carry no parabola: mixing them in would form inf - inf in the intersections.
// Every quantity is an integer below 2^53 or a ratio of two, and an intersection that rounding
// could misplace would have to lie within 1/(2n) of an integer without being one, so the
// result is exact.
void parabola_envelope(const double* f, int n, double* d, std::vector<int>& v,
                       std::vector<double>& z) {
  int k = -1;  // the last parabola of the envelope
  for (int q = 0; q < n; ++q) {
    if (f[q] == kEnvelopeInf) continue;
    const double fq = f[q] + double(q) * q;
    double s = -kEnvelopeInf;
    while (k >= 0) {
      const int r = v[k];
      s = (fq - (f[r] + double(r) * r)) / (2.0 * (q - r));
      if (s > z[k]) break;
      --k;  // parabola r is nowhere below the new one and its predecessors
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kEnvelopeInf : s;
    z[k + 1] = kEnvelopeInf;
  }
  if (k < 0) {
    std::fill(d, d + n, kEnvelopeInf);
    return;
  }
  int j = 0;
  for (int x = 0; x < n; ++x) {
    while (z[j + 1] < x) ++j;
    const double dx = x - v[j];
    d[x] = dx * dx + f[v[j]];
  }
}

}  // namespace

std::vector<double> squared_distance_transform(std::span<const std::uint8_t> occupied, int width,
                                               int height) {
  require(width > 0 && height > 0,
          "squared_distance_transform: expected a positive width and height, got {} x {}", width,
          height);
  const std::size_t w = static_cast<std::size_t>(width), h = static_cast<std::size_t>(height);
  require(occupied.size() == w * h,
          "squared_distance_transform: expected {} x {} = {} cells, got {}", width, height, w * h,
          occupied.size());
  std::vector<double> out(w * h);
  const int n_max = std::max(width, height);
  std::vector<double> f(static_cast<std::size_t>(n_max)), d(f.size());
  std::vector<int> v(f.size());
  std::vector<double> z(f.size() + 1);
  // Columns: the squared distance along y to the nearest occupied cell of the same column.
  for (std::size_t x = 0; x < w; ++x) {
    for (std::size_t y = 0; y < h; ++y) f[y] = occupied[y * w + x] != 0 ? 0.0 : kEnvelopeInf;
    parabola_envelope(f.data(), height, d.data(), v, z);
    for (std::size_t y = 0; y < h; ++y) out[y * w + x] = d[y];
  }
  // Rows: the nearest over every column of the column distances plus the squared x offset.
  for (std::size_t y = 0; y < h; ++y) {
    double* row = out.data() + y * w;
    std::copy(row, row + w, f.begin());
    parabola_envelope(f.data(), width, row, v, z);
  }
  return out;
}

DistanceField::DistanceField(const OccupancyGrid& grid, double max_distance) {
  require(!grid.empty(), "DistanceField: expected a grid with cells, got an empty one");
  require(std::isfinite(max_distance) && max_distance > 0,
          "DistanceField: expected a positive, finite max_distance [m], got {}", max_distance);
  require(max_distance >= std::numeric_limits<float>::min() &&
              max_distance <= std::numeric_limits<float>::max(),
          "DistanceField: expected a max_distance [m] within the range of float (distances are "
          "stored as float), got {}",
          max_distance);
  width_ = grid.width();
  height_ = grid.height();
  resolution_ = grid.resolution();
  inv_resolution_ = 1.0 / resolution_;
  origin_ = grid.origin();
  // Rounded to the storage precision, so that the capped cells, the padding and the value far
  // outside are one and the same number.
  max_distance_ = static_cast<float>(max_distance);

  // The transform runs on the grid padded by enough free cells that the distance at the outer
  // edge of the padding is at least max_distance: the field is then the true (capped) distance
  // to the map's occupied cells everywhere, continuous across the map's border, and equal to
  // max_distance wherever the padding ends. (A field padded with max_distance instead would
  // jump from 0 to max_distance next to a wall on the border, and bicubic interpolation would
  // overshoot below zero there.) Very long caps are limited to 4096 cells of padding.
  pad_ = static_cast<int>(std::min(4096.0, std::ceil(max_distance / resolution_) + 3.0));
  padded_width_ = width_ + 2 * pad_;
  const int padded_height = height_ + 2 * pad_;
  std::vector<std::uint8_t> occupied(
      static_cast<std::size_t>(padded_width_) * static_cast<std::size_t>(padded_height), 0);
  for (int iy = 0; iy < height_; ++iy)
    for (int ix = 0; ix < width_; ++ix)
      occupied[static_cast<std::size_t>(iy + pad_) * static_cast<std::size_t>(padded_width_) +
               static_cast<std::size_t>(ix + pad_)] = grid.is_occupied(ix, iy) ? 1 : 0;
  const std::vector<double> squared =
      squared_distance_transform(occupied, padded_width_, padded_height);
  padded_.resize(squared.size());
  for (std::size_t k = 0; k < squared.size(); ++k)
    padded_[k] = static_cast<float>(
        std::min(std::sqrt(squared[k]) * resolution_, static_cast<double>(max_distance_)));
  // Two cells inside the padding's edge, the 4 x 4 bicubic neighbourhood (the widest read)
  // still lies in it; beyond, the field is max_distance (exactly, when the padding is full).
  u_lo_ = v_lo_ = -(pad_ - 2.0);
  u_hi_ = width_ + pad_ - 2.0;
  v_hi_ = height_ + pad_ - 2.0;
}

double DistanceField::cell_distance(int ix, int iy) const { return value_at(ix, iy); }

double DistanceField::outside(double u, double v, Vec<2>* gradient) const {
  const bool nan = std::isnan(u) || std::isnan(v);
  const double value = nan ? std::numeric_limits<double>::quiet_NaN() : max_distance_;
  if (gradient != nullptr) gradient->setConstant(nan ? value : 0.0);
  return value;
}

double DistanceField::distance(const Vec<2>& p, Interpolation mode, Vec<2>* gradient) const {
  const detail::FieldLookup f = lookup();
  const double u = f.grid_u(p.x()), v = f.grid_v(p.y());
  if (!f.interpolates_at(u, v)) return outside(u, v, gradient);
  double du = 0.0, dv = 0.0, value = 0.0;
  const bool g = gradient != nullptr;
  switch (mode) {
    case Interpolation::kNearest:
      value = f.interpolate<Interpolation::kNearest, false>(u, v, nullptr, nullptr);
      break;
    case Interpolation::kBilinear:
      value = g ? f.interpolate<Interpolation::kBilinear, true>(u, v, &du, &dv)
                : f.interpolate<Interpolation::kBilinear, false>(u, v, nullptr, nullptr);
      break;
    case Interpolation::kBicubic:
      value = g ? f.interpolate<Interpolation::kBicubic, true>(u, v, &du, &dv)
                : f.interpolate<Interpolation::kBicubic, false>(u, v, nullptr, nullptr);
      break;
  }
  // Per cell to per metre (zero for kNearest).
  if (g) *gradient = Vec<2>(du * inv_resolution_, dv * inv_resolution_);
  return value;
}

}  // namespace implicit::robot
