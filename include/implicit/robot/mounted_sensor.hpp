#pragma once
// A range-bearing sensor mounted anywhere on the robot, with any bearing convention.
//
// The sensor sits at s = p + Rot(theta) (forward, left) on a robot with pose (p, theta), and
// measures a point landmark m as
//
//   h(x, m) = [ |m - s| ;  atan2(m2 - s2, m1 - s1) - theta + bearing_ahead ]
//
// bearing_ahead is the bearing of a landmark straight ahead: pi/2 for a SICK laser (0 = to the
// right, the convention of the plain-text log), 0 for the usual robotics convention (0 = ahead,
// counter-clockwise positive). With forward = left = 0 and bearing_ahead = pi/2 it is exactly
// RangeBearingSensor (the Ute's laser, whose state already is the laser's pose).
//
//   robot::MountedRangeBearingSensor laser({.forward = 0.3, .left = 0.0}, 0.01, 1e-4);
//   static_assert(robot::LandmarkSensorWithHessian<robot::MountedRangeBearingSensor>);
//
// One formula for h: measure() is templated on the scalar, so the Hessian comes from automatic
// differentiation (core/jet.hpp) of the same code; the Jacobian is written out (it is in the
// inner loop) and tested against the automatic one.

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/range_bearing.hpp"

namespace implicit::robot {

struct SensorMounting {
  double forward = 0.0;            ///< [m] ahead of the state's position
  double left = 0.0;               ///< [m] to the left of it
  double bearing_ahead = kPi / 2;  ///< bearing of a landmark straight ahead [rad]
};

class MountedRangeBearingSensor {
 public:
  static constexpr int MeasurementDim = 2;

  /// Sigma2 = diag(range_variance, bearing_variance) (variances, as RangeBearingSensor).
  explicit MountedRangeBearingSensor(SensorMounting mounting = {}, double range_variance = 0.05,
                                     double bearing_variance = 0.05 * kPi / 180.0)
      : mounting_(mounting), noise_(Vec<2>(range_variance, bearing_variance).asDiagonal()) {
    require(std::isfinite(mounting.forward) && std::isfinite(mounting.left) &&
                std::isfinite(mounting.bearing_ahead),
            "mounted range-bearing sensor: expected a finite mounting, got ({}, {}, {})",
            mounting.forward, mounting.left, mounting.bearing_ahead);
    require(range_variance > 0 && std::isfinite(range_variance),
            "mounted range-bearing sensor: expected a positive range variance, got {}",
            range_variance);
    require(bearing_variance > 0 && std::isfinite(bearing_variance),
            "mounted range-bearing sensor: expected a positive bearing variance, got {}",
            bearing_variance);
  }

  const SensorMounting& mounting() const { return mounting_; }
  const Mat2& noise_covariance() const { return noise_; }

  /// h(x, m) for any scalar type (double, or a jet for derivatives).
  template <typename T>
  Eigen::Matrix<T, 2, 1> measure(const Eigen::Matrix<T, 3, 1>& x, const Landmark& m) const {
    using std::atan2, std::cos, std::sin, std::sqrt;
    const T c = cos(x(2)), s = sin(x(2));
    const T dx = m(0) - (x(0) + c * mounting_.forward - s * mounting_.left);
    const T dy = m(1) - (x(1) + s * mounting_.forward + c * mounting_.left);
    return Eigen::Matrix<T, 2, 1>(sqrt(dx * dx + dy * dy),
                                  atan2(dy, dx) - x(2) + mounting_.bearing_ahead);
  }

  Measurement predict(const Pose& x, const Landmark& m) const { return measure<double>(x, m); }

  /// e = (r_hat - z_r, wrap(b_hat - z_b)).
  static Measurement residual(const Measurement& predicted, const Measurement& z) {
    return RangeBearingSensor::residual(predicted, z);
  }

  /// h and J_h_x (2x3) together (range_bearing_with_jacobian, with the sensor's offset from the
  /// state d = m - s and q = d s / d heading).
  void predict_with_jacobian(const Pose& x, const Landmark& m, Measurement& h, Mat23& j) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const double a = mounting_.forward, b = mounting_.left;
    range_bearing_with_jacobian(m(0) - (x(0) + c * a - s * b), m(1) - (x(1) + s * a + c * b),
                                -s * a - c * b, c * a - s * b, h, j);
    h(1) = h(1) - x(2) + mounting_.bearing_ahead;
  }

  Mat23 jacobian_pose(const Pose& x, const Landmark& m) const {
    Measurement h;
    Mat23 j;
    predict_with_jacobian(x, m, h, j);
    return j;
  }

  /// Second derivatives of r and b with respect to the pose, by automatic differentiation of
  /// measure() (the heading entries are not zero once the sensor is off the state's position).
  void hessian_pose(const Pose& x, const Landmark& m, Mat3& range_hessian,
                    Mat3& bearing_hessian) const {
    auto range = [&](const auto& xj) { return measure(xj, m)(0); };
    auto bearing = [&](const auto& xj) { return measure(xj, m)(1); };
    range_hessian = std::get<2>(autodiff_hessian<3>(range, x));
    bearing_hessian = std::get<2>(autodiff_hessian<3>(bearing, x));
  }

  /// J_h_m (2x2): h depends on m only through d = m - s.
  Mat2 jacobian_landmark(const Pose& x, const Landmark& m) const {
    return -jacobian_pose(x, m).leftCols<2>();
  }

  /// Landmark position that would produce measurement z from pose x.
  Landmark inverse(const Pose& x, const Measurement& z) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const double a = mounting_.forward, b = mounting_.left;
    const double angle = x(2) + z(1) - mounting_.bearing_ahead;
    return Landmark(x(0) + c * a - s * b + z(0) * std::cos(angle),
                    x(1) + s * a + c * b + z(0) * std::sin(angle));
  }

 private:
  SensorMounting mounting_;
  Mat2 noise_;
};

}  // namespace implicit::robot
