#include "implicit/robot/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

// Catmull-Rom weights of the samples at offsets -1, 0, 1, 2 for a point t in [0, 1) past
// sample 0, and their derivatives in t (Keys' cubic convolution with a = -1/2).
void catmull_rom_weights(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
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
  std::vector<std::uint8_t> occupied(static_cast<std::size_t>(padded_width_) *
                                         static_cast<std::size_t>(padded_height),
                                     0);
  for (int iy = 0; iy < height_; ++iy)
    for (int ix = 0; ix < width_; ++ix)
      occupied[static_cast<std::size_t>(iy + pad_) * static_cast<std::size_t>(padded_width_) +
               static_cast<std::size_t>(ix + pad_)] = grid.is_occupied(ix, iy) ? 1 : 0;
  const std::vector<double> squared =
      squared_distance_transform(occupied, padded_width_, padded_height);
  padded_.resize(squared.size());
  for (std::size_t k = 0; k < squared.size(); ++k)
    padded_[k] = static_cast<float>(std::min(std::sqrt(squared[k]) * resolution_,
                                             static_cast<double>(max_distance_)));
  // Two cells inside the padding's edge, the 4 x 4 bicubic neighbourhood (the widest read)
  // still lies in it; beyond, the field is max_distance (exactly, when the padding is full).
  u_lo_ = v_lo_ = -(pad_ - 2.0);
  u_hi_ = width_ + pad_ - 2.0;
  v_hi_ = height_ + pad_ - 2.0;
}

double DistanceField::cell_distance(int ix, int iy) const { return value_at(ix, iy); }

void DistanceField::gather(int ix, int iy, int n, float* out) const {
  if (ix >= -pad_ && iy >= -pad_ && ix + n <= width_ + pad_ && iy + n <= height_ + pad_) {
    // The common case: n rows of n contiguous cells, no bounds to check.
    const float* p = padded_.data() +
                     static_cast<std::size_t>(iy + pad_) * static_cast<std::size_t>(padded_width_) +
                     static_cast<std::size_t>(ix + pad_);
    for (int j = 0; j < n; ++j, p += padded_width_)
      for (int i = 0; i < n; ++i) out[j * n + i] = p[i];
    return;
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) out[j * n + i] = value_at(ix + i, iy + j);
}

double DistanceField::outside(double u, double v, Vec<2>* gradient) const {
  const bool nan = std::isnan(u) || std::isnan(v);
  const double value = nan ? std::numeric_limits<double>::quiet_NaN() : max_distance_;
  if (gradient != nullptr) gradient->setConstant(nan ? value : 0.0);
  return value;
}

double DistanceField::distance(const Vec<2>& p, Interpolation mode, Vec<2>* gradient) const {
  // Grid coordinates in cells: cell i spans [i, i + 1), its centre is at i + 1/2.
  const double u = (p.x() - origin_.x()) * inv_resolution_;
  const double v = (p.y() - origin_.y()) * inv_resolution_;
  if (!(u > u_lo_ && u < u_hi_ && v > v_lo_ && v < v_hi_)) return outside(u, v, gradient);

  // Floors by truncation of a positive number (u, v > 2 - pad_ here): std::floor is a library call
  // on plain x86-64. A coordinate within an ulp below an integer may round up to it when
  // shifted, which moves it to the next cell with an offset of -1e-16: the same value.
  if (mode == Interpolation::kNearest) {
    if (gradient != nullptr) gradient->setZero();
    return value_at(static_cast<int>(u + pad_) - pad_, static_cast<int>(v + pad_) - pad_);
  }
  // Offsets from the centres: a lies between the centres of cells i0 and i0 + 1.
  const double a = u - 0.5, b = v - 0.5;
  const int i0 = static_cast<int>(a + pad_) - pad_, j0 = static_cast<int>(b + pad_) - pad_;
  const double tx = a - i0, ty = b - j0;

  if (mode == Interpolation::kBilinear) {
    float c[4];
    gather(i0, j0, 2, c);
    // Differences in double: float ones would round to 1e-7 of the distances.
    const double c00 = c[0], c10 = c[1], c01 = c[2], c11 = c[3];
    const double bottom = c00 + tx * (c10 - c00), top = c01 + tx * (c11 - c01);
    if (gradient != nullptr)
      *gradient = Vec<2>(((1 - ty) * (c10 - c00) + ty * (c11 - c01)) * inv_resolution_,
                         (top - bottom) * inv_resolution_);
    return bottom + ty * (top - bottom);
  }

  float c[16];
  gather(i0 - 1, j0 - 1, 4, c);
  double wx[4], dwx[4], wy[4], dwy[4];
  catmull_rom_weights(tx, wx, dwx);
  catmull_rom_weights(ty, wy, dwy);
  double value = 0.0, du = 0.0, dv = 0.0;
  for (int j = 0; j < 4; ++j) {
    double row = 0.0, drow = 0.0;  // the row interpolated along x, and its x derivative
    for (int i = 0; i < 4; ++i) {
      row += wx[i] * c[j * 4 + i];
      drow += dwx[i] * c[j * 4 + i];
    }
    value += wy[j] * row;
    du += wy[j] * drow;
    dv += dwy[j] * row;
  }
  if (gradient != nullptr) *gradient = Vec<2>(du * inv_resolution_, dv * inv_resolution_);
  return value;
}

}  // namespace implicit::robot
