#pragma once
// Range-bearing landmark sensor (a laser that sees point landmarks), spec §3.2.
//
//   h(x, m) = [ r ; b ] = [ |m - p| ;  atan2(m2 - y, m1 - x) - beta + pi/2 ],   p = (x, y)
//   z = h + v,  v ~ N(0, Sigma2)
//
// Bearing convention (SICK): 0 = to the right, pi/2 = straight ahead, pi = to the left. Residuals
// are always wrapped to [-pi, pi); the state heading is never wrapped. Sigma2 = diag(var_r, var_b)
// holds VARIANCES by default (0.05 m^2, 8.7266e-4 rad^2, spec E27); from_std() builds it from
// standard deviations instead.
//
//   RangeBearingSensor s;                       // paper defaults
//   Vec<2> zhat = s.predict(pose, landmark);
//   Vec<2> e = s.residual(zhat, z);             // (r_hat - z_r, wrap(b_hat - z_b))
//   Mat<2,3> H = s.jacobian_pose(pose, landmark);
//
// Mistake to avoid: differentiating through a landmark at the sensor (r = 0): the Jacobians are
// singular there; filters should reject observations with r below min_range.

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// The one range-bearing Jacobian of the library. For a sensor at s(x) seeing the landmark at
/// offset d = m - s, with q = d s / d heading (zero for a sensor at the state's position):
///   h = (|d|, atan2(d2, d1)),   the heading term of the bearing (- heading + convention) is
///   the caller's, and J_h_x is
///   [[ -d1 / r, -d2 / r, -(d . q) / r ], [ d2 / r^2, -d1 / r^2, (d2 q1 - d1 q2) / r^2 - 1 ]].
inline void range_bearing_with_jacobian(double d1, double d2, double q1, double q2, Measurement& h,
                                        Mat23& j) {
  const double r2 = d1 * d1 + d2 * d2, r = std::sqrt(r2);
  h(0) = r;
  h(1) = std::atan2(d2, d1);
  j << -d1 / r, -d2 / r, -(d1 * q1 + d2 * q2) / r, d2 / r2, -d1 / r2,
      (d2 * q1 - d1 * q2) / r2 - 1.0;
}

class RangeBearingSensor {
 public:
  static constexpr int MeasurementDim = 2;

  /// Sigma2 = diag(range_variance, bearing_variance).
  explicit RangeBearingSensor(double range_variance = 0.05,
                              double bearing_variance = 0.05 * kPi / 180.0)
      : noise_(Vec<2>(range_variance, bearing_variance).asDiagonal()) {
    require(range_variance > 0 && std::isfinite(range_variance),
            "range-bearing sensor: expected a positive range variance, got {}", range_variance);
    require(bearing_variance > 0 && std::isfinite(bearing_variance),
            "range-bearing sensor: expected a positive bearing variance, got {}", bearing_variance);
  }
  /// Sigma2 from standard deviations (the other reading of the paper's Table 7).
  static RangeBearingSensor from_std(double range_std, double bearing_std) {
    return RangeBearingSensor(range_std * range_std, bearing_std * bearing_std);
  }

  const Mat2& noise_covariance() const { return noise_; }

  Measurement predict(const Pose& x, const Landmark& m) const {
    const double dx = m(0) - x(0), dy = m(1) - x(1);
    return Measurement(std::hypot(dx, dy), std::atan2(dy, dx) - x(2) + kPi / 2.0);
  }

  /// The predicted range alone (first component of predict()), cheaper than predict(): lets
  /// data association skip landmarks whose range cannot pass the gate before any atan2.
  double range(const Pose& x, const Landmark& m) const {
    return std::hypot(m(0) - x(0), m(1) - x(1));
  }

  /// e = (r_hat - z_r, wrap(b_hat - z_b)).
  static Measurement residual(const Measurement& predicted, const Measurement& z) {
    return Measurement(predicted(0) - z(0), wrap_angle(predicted(1) - z(1)));
  }

  /// J_h_x (2x3).
  Mat23 jacobian_pose(const Pose& x, const Landmark& m) const {
    Measurement h;
    Mat23 j;
    predict_with_jacobian(x, m, h, j);
    return j;
  }

  /// predict() and jacobian_pose() in one pass (one square root, one atan2 instead of a hypot, an
  /// atan2 and a square root): the per-particle filter updates call this in their inner loops.
  void predict_with_jacobian(const Pose& x, const Landmark& m, Measurement& h, Mat23& j) const {
    // The sensor is at the state: it does not move with the heading (q = 0).
    range_bearing_with_jacobian(m(0) - x(0), m(1) - x(1), 0.0, 0.0, h, j);
    h(1) = h(1) - x(2) + kPi / 2.0;  // the order of the other predictions: same bits
  }

  /// Second derivatives of h with respect to the pose (spec §3.3), with dx = x - m1, dy = y - m2:
  ///   d2r (x,y block) = [[dy^2, -dx dy], [-dx dy, dx^2]] / r^3
  ///   d2b (x,y block) = [[2 dx dy, dy^2 - dx^2], [dy^2 - dx^2, -2 dx dy]] / r^4
  /// Every heading entry is zero (r does not depend on beta, b is linear in it).
  void hessian_pose(const Pose& x, const Landmark& m, Mat3& range_hessian,
                    Mat3& bearing_hessian) const {
    const double dx = x(0) - m(0), dy = x(1) - m(1);
    const double r2 = dx * dx + dy * dy, r = std::sqrt(r2);
    const double r3 = r2 * r, r4 = r2 * r2;
    range_hessian.setZero();
    range_hessian(0, 0) = dy * dy / r3;
    range_hessian(0, 1) = range_hessian(1, 0) = -dx * dy / r3;
    range_hessian(1, 1) = dx * dx / r3;
    bearing_hessian.setZero();
    bearing_hessian(0, 0) = 2.0 * dx * dy / r4;
    bearing_hessian(0, 1) = bearing_hessian(1, 0) = (dy * dy - dx * dx) / r4;
    bearing_hessian(1, 1) = -2.0 * dx * dy / r4;
  }

  /// J_h_m (2x2) = minus the position part of J_h_x.
  Mat2 jacobian_landmark(const Pose& x, const Landmark& m) const {
    return -jacobian_pose(x, m).leftCols<2>();
  }

  /// Landmark position that would produce measurement z from pose x (new-landmark initialisation).
  static Landmark inverse(const Pose& x, const Measurement& z) {
    const double angle = x(2) + z(1) - kPi / 2.0;
    return Landmark(x(0) + z(0) * std::cos(angle), x(1) + z(0) * std::sin(angle));
  }

  /// J_g_z (2x2) of inverse() with respect to the measurement.
  static Mat2 inverse_jacobian_measurement(const Pose& x, const Measurement& z) {
    const double angle = x(2) + z(1) - kPi / 2.0;
    const double c = std::cos(angle), s = std::sin(angle);
    Mat2 j;
    j << c, -z(0) * s, s, z(0) * c;
    return j;
  }

 private:
  Mat2 noise_;
};

}  // namespace implicit::robot
