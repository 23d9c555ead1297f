#pragma once
// The per-point lookups of DistanceField (distance_field.hpp), shared by distance() and the
// likelihood field's loops over a scan's beams (likelihood_field.cpp). A loop takes the field's
// constants once, as a FieldLookup value held in registers (read through the field, they would
// be reloaded after every store the compiler cannot tell apart from them), and the lookups are
// templates on the interpolation and on whether the gradient is wanted: a loop over beams
// compiles to straight-line code, without a mode switch per beam, without derivative weights
// when only values are needed, and without a bounds check per cell (the caller has checked
// interpolates_at()).

#include <cstddef>

#include <Eigen/Core>

#include "implicit/robot/distance_field.hpp"

namespace implicit::robot::detail {

// Catmull-Rom weights of the samples at offsets -1, 0, 1, 2 for a point t in [0, 1) past
// sample 0 (Keys' cubic convolution with a = -1/2).
inline void catmull_rom_weights(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}

// Their derivatives in t.
inline void catmull_rom_derivatives(double t, double dw[4]) {
  const double t2 = t * t;
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
}

struct FieldLookup {
  const float* cells;  ///< the padded cells, row-major, row 0 lowest y
  std::size_t stride;  ///< cells per padded row
  double pad;          ///< cells of padding on each side
  double origin_x, origin_y, inv_resolution;
  double u_lo, u_hi, v_lo, v_hi;  ///< where the modes interpolate (DistanceField)

  /// Grid coordinates in cells of world point (x, y): cell i spans [i, i + 1).
  double grid_u(double x) const { return (x - origin_x) * inv_resolution; }
  double grid_v(double y) const { return (y - origin_y) * inv_resolution; }
  /// Whether (u, v) lies where the modes interpolate (false for NaN); elsewhere the field is
  /// max_distance.
  bool interpolates_at(double u, double v) const {
    return u > u_lo && u < u_hi && v > v_lo && v < v_hi;
  }
  /// The index in the padded cells of the cell containing (u, v); interpolates_at(u, v).
  std::size_t cell_index(double u, double v) const {
    // Floors by truncation of a positive number (u, v > 2 - pad inside): std::floor is a
    // library call on plain x86-64. A coordinate within an ulp below an integer may round up to
    // it when shifted, which moves it to the next cell with an offset of -1e-16: the same value.
    return static_cast<std::size_t>(static_cast<int>(v + pad)) * stride +
           static_cast<std::size_t>(static_cast<int>(u + pad));
  }

  /// The interpolated distance at (u, v) and, when Gradient, its derivatives in u and v (per
  /// cell); interpolates_at(u, v) must hold.
  template <Interpolation Mode, bool Gradient>
  double interpolate(double u, double v, double* du, double* dv) const {
    if constexpr (Mode == Interpolation::kNearest) {
      if constexpr (Gradient) *du = *dv = 0.0;
      return cells[cell_index(u, v)];
    } else {
      // Offsets from the centres: a lies between the centres of cells i0 and i0 + 1 (padded
      // indices pi0 = i0 + pad). Inside interpolates_at() the 4 x 4 neighbourhood of the widest
      // (bicubic) read lies in the padded cells.
      const double a = u - 0.5, b = v - 0.5;
      const int pi0 = static_cast<int>(a + pad), pj0 = static_cast<int>(b + pad);
      const double tx = a - (pi0 - pad), ty = b - (pj0 - pad);
      const float* c =
          cells + static_cast<std::size_t>(pj0) * stride + static_cast<std::size_t>(pi0);
      if constexpr (Mode == Interpolation::kBilinear) {
        // Differences in double: float ones would round to 1e-7 of the distances.
        const double c00 = c[0], c10 = c[1], c01 = c[stride], c11 = c[stride + 1];
        const double bottom = c00 + tx * (c10 - c00), top = c01 + tx * (c11 - c01);
        if constexpr (Gradient) {
          *du = (1 - ty) * (c10 - c00) + ty * (c11 - c01);
          *dv = top - bottom;
        }
        return bottom + ty * (top - bottom);
      } else {
        return bicubic<Gradient>(c - stride - 1, tx, ty, du, dv);
      }
    }
  }

  /// Catmull-Rom over the 4 x 4 cells from c (row by row) at offsets (tx, ty) past the second.
  template <bool Gradient>
  double bicubic(const float* c, double tx, double ty, double* du, double* dv) const {
    double wx[4], wy[4];
    catmull_rom_weights(tx, wx);
    catmull_rom_weights(ty, wy);
    [[maybe_unused]] double dwx[4], dwy[4];
    if constexpr (Gradient) {
      catmull_rom_derivatives(tx, dwx);
      catmull_rom_derivatives(ty, dwy);
    }
    // Along y first: the four columns interpolated at ty (and their y derivatives), as two
    // pairs of columns (one SSE2 register each); then along x.
    using Pair = Eigen::Array2d;
    const auto pair = [](const float* p) { return Pair(p[0], p[1]); };
    Pair lo = wy[0] * pair(c), hi = wy[0] * pair(c + 2);
    [[maybe_unused]] Pair dlo, dhi;
    if constexpr (Gradient) {
      dlo = dwy[0] * pair(c);
      dhi = dwy[0] * pair(c + 2);
    }
    for (int j = 1; j < 4; ++j) {
      c += stride;
      const Pair l = pair(c), h = pair(c + 2);
      lo += wy[j] * l;
      hi += wy[j] * h;
      if constexpr (Gradient) {
        dlo += dwy[j] * l;
        dhi += dwy[j] * h;
      }
    }
    const Pair wlo(wx[0], wx[1]), whi(wx[2], wx[3]);
    if constexpr (Gradient) {
      *du = (Pair(dwx[0], dwx[1]) * lo + Pair(dwx[2], dwx[3]) * hi).sum();
      *dv = (wlo * dlo + whi * dhi).sum();
    }
    return (wlo * lo + whi * hi).sum();
  }
};

}  // namespace implicit::robot::detail

namespace implicit::robot {

inline detail::FieldLookup DistanceField::lookup() const {
  return {padded_.data(),
          static_cast<std::size_t>(padded_width_),
          static_cast<double>(pad_),
          origin_.x(),
          origin_.y(),
          inv_resolution_,
          u_lo_,
          u_hi_,
          v_lo_,
          v_hi_};
}

}  // namespace implicit::robot
