#pragma once
// The Ute: a car-like vehicle whose state is the LASER's position and heading (spec §3.1).
//
// State x = (x, y, beta) [m, m, rad]; control u = (vc, alpha): axle-centre speed [m/s] and
// steering angle [rad]. Over one step of length dt:
//
//   x_n = x_{n-1} + dt R(x_{n-1}, u_n) + w_n,   w_n ~ N(0, Sigma1(x_{n-1}, u_n))
//   R(x, u) = vc g(beta, alpha),
//   g = [cos b - (tan a/L)(a_ sin b + b_ cos b);  sin b + (tan a/L)(a_ cos b - b_ sin b);  tan a/L]
//   Sigma1 = dt (dR/du P P^T dR/du^T + Q Q^T)       (P, Q are square-root, "diffusion", matrices)
//
// Derivative convention (used by every model in robot/): J_out_in = d out / d in, e.g.
// jacobian_state = d f / d x (3x3), rate_jacobian_control = d R / d u (3x2).
// Common mistakes: feeding the encoder speed (rear-left wheel) instead of the axle speed
// (use axle_speed()), and reading P and Q as covariances (they are standard deviations).

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

// Pose = (x, y, beta) and Control = (vc [m/s] axle speed, alpha [rad] steering) here.

/// Parameters of the Ute (paper Table 7, corrected per spec E25-E27).
struct UteParams {
  double wheelbase = 2.83;       ///< L [m]
  double encoder_offset = 0.76;  ///< H [m]: rear-left encoder to axle centre
  double laser_forward = 3.78;   ///< a [m]: laser ahead of the rear axle
  double laser_left = 0.5;       ///< b [m]: laser to the left
  double dt = 0.025;             ///< delta [s]: motion step
  Vec<2> control_std{0.5, 0.5};  ///< P = diag(p1, p2): speed [m/s] and steering [rad] noise
  Vec<3> state_std{0.1, 0.1, 0.1 * kPi / 180.0};  ///< Q = diag(q1, q2, q3)

  void validate() const {
    require(wheelbase > 0 && std::isfinite(wheelbase), "Ute wheelbase L: expected > 0, got {}",
            wheelbase);
    require(dt > 0 && std::isfinite(dt), "Ute time step dt: expected > 0, got {}", dt);
    require((control_std.array() >= 0).all() && control_std.allFinite(),
            "Ute control noise P: expected finite non-negative std devs, got ({}, {})",
            control_std(0), control_std(1));
    require((state_std.array() > 0).all() && state_std.allFinite(),
            "Ute state noise Q: expected finite positive std devs, got ({}, {}, {})", state_std(0),
            state_std(1), state_std(2));
  }
};

/// The Ute kinematic model with analytic Jacobians. Immutable; cheap to copy.
class UteModel {
 public:
  static constexpr int StateDim = 3;
  static constexpr int ControlDim = 2;

  explicit UteModel(const UteParams& p = {}) : p_(p) { p_.validate(); }
  const UteParams& params() const { return p_; }
  double dt() const { return p_.dt; }

  /// The same vehicle over a step of length dt (the filters step on the log's own time stamps).
  UteModel with_dt(double dt) const {
    UteParams p = p_;
    p.dt = dt;
    return UteModel(p);
  }

  /// Axle-centre speed from the rear-left encoder speed: vc = ve / (1 - tan(alpha) H / L).
  double axle_speed(double encoder_speed, double alpha) const {
    return encoder_speed / (1.0 - std::tan(alpha) * p_.encoder_offset / p_.wheelbase);
  }

  /// R(x, u): the state rate.
  Pose rate(const Pose& x, const Control& u) const { return u(0) * direction(x(2), u(1)); }

  /// f(x, u) = x + dt R(x, u): the mean of the next state.
  Pose predict(const Pose& x, const Control& u) const { return x + p_.dt * rate(x, u); }

  /// J_f_x = I + dt dR/dx (R depends on the heading only).
  Mat3 jacobian_state(const Pose& x, const Control& u) const {
    const double t = std::tan(u(1)) / p_.wheelbase;
    const double s = std::sin(x(2)), c = std::cos(x(2));
    const double a = p_.laser_forward, b = p_.laser_left;
    Mat3 j = Mat3::Identity();
    j(0, 2) = p_.dt * u(0) * (-s - t * (a * c - b * s));
    j(1, 2) = p_.dt * u(0) * (c + t * (-a * s - b * c));
    return j;
  }

  /// J_R_u = dR/du = [g, c k], c = vc sec^2(alpha) / L, k = [-(a sin + b cos); a cos - b sin; 1].
  Mat32 rate_jacobian_control(const Pose& x, const Control& u) const {
    Mat32 j;
    j.col(0) = direction(x(2), u(1));
    const double ca = std::cos(u(1));
    const double cfac = u(0) / (ca * ca * p_.wheelbase);
    const double s = std::sin(x(2)), c = std::cos(x(2));
    j.col(1) << -cfac * (p_.laser_forward * s + p_.laser_left * c),
        cfac * (p_.laser_forward * c - p_.laser_left * s), cfac;
    return j;
  }

  /// Sigma1(x, u) = dt (dR/du P P^T dR/du^T + Q Q^T): process noise covariance of one step.
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    const Mat32 j = rate_jacobian_control(x, u);
    const Mat32 jp = j * p_.control_std.asDiagonal();
    Mat3 s = jp * jp.transpose();
    s.diagonal() += p_.state_std.cwiseAbs2();
    return p_.dt * s;
  }

  /// predict() and process_covariance() together, sharing the trigonometry (one sincos of the
  /// heading, one tan and one cos of the steering instead of four and three): the filters call
  /// both for every particle at every step.
  void predict_with_covariance(const Pose& x, const Control& u, Pose& mean,
                               Mat3& covariance) const {
    const double ta = std::tan(u(1)), ca = std::cos(u(1));
    const double t = ta / p_.wheelbase;
    const double s = std::sin(x(2)), c = std::cos(x(2));
    const double a = p_.laser_forward, b = p_.laser_left;
    const Vec<3> g(c - t * (a * s + b * c), s + t * (a * c - b * s), t);  // direction()
    mean = x + (p_.dt * u(0)) * g;
    const double cfac = u(0) / (ca * ca * p_.wheelbase);
    const Vec<3> k(-cfac * (a * s + b * c), cfac * (a * c - b * s), cfac);  // dR/d alpha
    const double p1 = p_.control_std(0), p2 = p_.control_std(1);
    const Vec<3> g1 = p1 * g, k2 = p2 * k;
    covariance = g1 * g1.transpose() + k2 * k2.transpose();
    covariance.diagonal() += p_.state_std.cwiseAbs2();
    covariance *= p_.dt;
  }

 private:
  Pose direction(double beta, double alpha) const {
    const double t = std::tan(alpha) / p_.wheelbase;
    const double s = std::sin(beta), c = std::cos(beta);
    const double a = p_.laser_forward, b = p_.laser_left;
    return Pose(c - t * (a * s + b * c), s + t * (a * c - b * s), t);
  }
  UteParams p_;
};

}  // namespace implicit::robot
