#pragma once
// A unicycle / differential-drive robot: state (x, y, heading) of the robot's centre, control
// (v, omega) = forward speed [m/s] and turn rate [rad/s], from wheel odometry.
//
//   x_n = x_{n-1} + dt R(x_{n-1}, u_n) + w_n,   R(x, u) = (v cos theta, v sin theta, omega)
//   w_n ~ N(0, Sigma1),  Sigma1 = dt (dR/du P P^T dR/du^T + Q Q^T),  P = diag(sd_v, sd_omega)
//
// Noise enters through v and omega (the odometry) plus a small state noise Q that keeps Sigma1
// positive definite when the robot stands still. v = 0 with omega != 0 turns on the spot.
// Each step may have its own length: with_dt(dt) returns the same model for a step of length dt
// (the filters call it with the log's own time stamps).
//
//   robot::UnicycleModel model({.dt = 0.1});
//   Pose next = model.predict(pose, Control(1.0, 0.2));   // v = 1 m/s, omega = 0.2 rad/s

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

struct UnicycleParams {
  double dt = 0.1;                                ///< nominal step length [s]
  Vec<2> control_std{0.1, 0.05};                  ///< sd of v [m/s] and omega [rad/s]
  Vec<3> state_std{0.02, 0.02, 0.2 * kPi / 180};  ///< Q = diag(q1, q2, q3), per sqrt(s)

  void validate() const {
    require(dt > 0 && std::isfinite(dt), "unicycle time step dt: expected > 0, got {}", dt);
    require((control_std.array() >= 0).all() && control_std.allFinite(),
            "unicycle control noise: expected finite non-negative std devs, got ({}, {})",
            control_std(0), control_std(1));
    require((state_std.array() > 0).all() && state_std.allFinite(),
            "unicycle state noise Q: expected finite positive std devs, got ({}, {}, {})",
            state_std(0), state_std(1), state_std(2));
  }
};

/// The unicycle kinematic model with analytic Jacobians. Immutable; cheap to copy.
class UnicycleModel {
 public:
  static constexpr int StateDim = 3;
  static constexpr int ControlDim = 2;

  explicit UnicycleModel(const UnicycleParams& p = {}) : p_(p) { p_.validate(); }
  const UnicycleParams& params() const { return p_; }
  double dt() const { return p_.dt; }

  /// The same robot over a step of length dt.
  UnicycleModel with_dt(double dt) const {
    UnicycleParams p = p_;
    p.dt = dt;
    return UnicycleModel(p);
  }

  /// f(x, u) = x + dt R(x, u).
  Pose predict(const Pose& x, const Control& u) const {
    return x + p_.dt * Pose(u(0) * std::cos(x(2)), u(0) * std::sin(x(2)), u(1));
  }

  /// J_f_x = I + dt dR/dx (R depends on the heading only).
  Mat3 jacobian_state(const Pose& x, const Control& u) const {
    Mat3 j = Mat3::Identity();
    j(0, 2) = -p_.dt * u(0) * std::sin(x(2));
    j(1, 2) = p_.dt * u(0) * std::cos(x(2));
    return j;
  }

  /// Sigma1 = dt (dR/du P P^T dR/du^T + Q Q^T) with dR/du = [[cos, 0], [sin, 0], [0, 1]].
  Mat3 process_covariance(const Pose& x, const Control& /*u*/) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const double v2 = p_.control_std(0) * p_.control_std(0);
    Mat3 sigma;
    sigma << v2 * c * c, v2 * c * s, 0.0, v2 * c * s, v2 * s * s, 0.0, 0.0, 0.0,
        p_.control_std(1) * p_.control_std(1);
    sigma.diagonal() += p_.state_std.cwiseAbs2();
    return p_.dt * sigma;
  }

 private:
  UnicycleParams p_;
};

}  // namespace implicit::robot
