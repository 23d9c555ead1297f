#pragma once
// The odometry motion model of a differential-drive robot (Thrun, Burgard & Fox, Probabilistic
// Robotics, §5.4), with the noise parameters alpha1..alpha4 named as in nav2's AMCL.
//
// The control of one step is the odometry increment u = between(odom_{n-1}, odom_n) =
// (dx, dy, dtheta), given in the previous odometry frame. It is read as three motions: a turn
// rot1 towards the direction of travel, a straight move trans, a turn rot2 to the new heading:
//
//   trans = |(dx, dy)|,  rot1 = atan2(dy, dx) (0 when trans < 1e-9 m),  rot2 = dtheta - rot1
//
// and each of the three is perturbed by zero-mean Gaussian noise with variances
//
//   var_rot1  = alpha1 rot1^2 + alpha2 trans^2
//   var_trans = alpha3 trans^2 + alpha4 (rot1^2 + rot2^2)
//   var_rot2  = alpha1 rot2^2 + alpha2 trans^2
//
// Two departures from the textbook, because odometry between laser scans is often short or
// backward (nav2 makes both too, in its own way):
//  * backward motion: when the robot backs up, rot1 = atan2(dy, dx) is near ±pi and rot2 near
//    dtheta ∓ pi. For the noise, a step with |rot1| > pi/2 is read as backing up: its rotations
//    count as rot1 - pi and rot2 + pi (wrapped), so backing up 1 m is as noisy as driving forward
//    1 m, not a half turn and back. (nav2 folds each rotation to its distance from 0 or pi on its
//    own, which also makes a half turn on the spot noiseless; we fold only when backing up.)
//  * steps shorter than kOdometryMinTravel (1 cm, nav2's threshold): the direction of travel is
//    then jitter, not motion, so the noise counts rot1 as 0 and rot2 as dtheta (a turn on the
//    spot). Without this, a sideways millimetre would count as a quarter turn twice.
// The nominal motion is always the exact decomposition above, so the noiseless step is x ⊕ u.
// rot2 is kept as dtheta - rot1 without wrapping, so that rot1 + rot2 = dtheta and headings stay
// continuous (robot/types.hpp); the noise wraps it.
//
// The model comes in two forms:
//  * the Gaussian form the filters use (predict, process_covariance): x_n ~ N(x ⊕ u, Sigma) with
//    Sigma = J diag(var_rot1, var_trans, var_rot2) J^T + diag(floor_std^2), J the Jacobian of
//    the world-frame pose reached with respect to (rot1, trans, rot2) at the nominal motion. The
//    linearisation is accurate when the noise is small (a few degrees); the floor keeps Sigma
//    positive definite when the robot stands still (all variances are then 0);
//  * the exact sampler (sample), what nav2's AMCL does: draw rot1, trans, rot2 with their noise
//    and compose. Its draws are banana-shaped for large noise; it has no floor.
//
//   robot::OdometryModel model({.alpha1 = 0.05, .alpha2 = 0.05, .alpha3 = 0.05, .alpha4 = 0.05});
//   OdometryDelta u = between(odom_prev, odom_now);
//   Pose mean = model.predict(x, u);                      // = compose(x, u)
//   Mat3 sigma = model.process_covariance(x, u);
//   Pose draw = model.sample(x, u, rng);                  // nav2's sampler

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// An odometry increment (dx [m], dy [m], dtheta [rad]) in the previous odometry frame.
using OdometryDelta = Vec<3>;

/// Noise of the odometry model; the variances grow with the squares of the motions (see above).
struct OdometryAlphas {
  double alpha1 = 0.2;  ///< rotation noise from rotation
  double alpha2 = 0.2;  ///< rotation noise from translation
  double alpha3 = 0.2;  ///< translation noise from translation
  double alpha4 = 0.2;  ///< translation noise from rotation

  void validate() const {
    const double values[4] = {alpha1, alpha2, alpha3, alpha4};
    const char* meanings[4] = {"rotation noise from rotation", "rotation noise from translation",
                               "translation noise from translation",
                               "translation noise from rotation"};
    for (int k = 0; k < 4; ++k)
      require(std::isfinite(values[k]) && values[k] >= 0,
              "odometry alpha{} ({}): expected a finite value >= 0, got {}", k + 1, meanings[k],
              values[k]);
  }
};

/// One step as three motions: turn rot1, move trans (>= 0), turn rot2.
struct OdometryMotion {
  double rot1 = 0.0, trans = 0.0, rot2 = 0.0;
};

/// Below this distance [m] the direction of travel is not used as a rotation: rot1 = 0.
inline constexpr double kOdometryMinDirection = 1e-9;
/// Below this distance [m] the noise treats a step as a turn on the spot (as nav2 does).
inline constexpr double kOdometryMinTravel = 0.01;

/// The exact decomposition of u: compose_motion(x, decompose_odometry(u)) = x ⊕ u.
inline OdometryMotion decompose_odometry(const OdometryDelta& u) {
  OdometryMotion m;
  m.trans = std::hypot(u(0), u(1));
  m.rot1 = m.trans < kOdometryMinDirection ? 0.0 : std::atan2(u(1), u(0));
  m.rot2 = u(2) - m.rot1;
  return m;
}

/// The pose reached from x by turning m.rot1, moving m.trans and turning m.rot2.
inline Pose compose_motion(const Pose& x, const OdometryMotion& m) {
  const double direction = x(2) + m.rot1;
  return Pose(x(0) + m.trans * std::cos(direction), x(1) + m.trans * std::sin(direction),
              x(2) + m.rot1 + m.rot2);
}

/// The magnitudes (|rot1|, |rot2|) that the noise counts for the step u: wrapped, read as backing
/// up when |rot1| > pi/2, and (0, |dtheta|) for steps shorter than kOdometryMinTravel.
inline Vec<2> odometry_noise_rotations(const OdometryDelta& u) {
  const OdometryMotion m = decompose_odometry(u);
  const auto wrapped = [](double a) { return std::abs(std::remainder(a, 2.0 * kPi)); };
  if (m.trans < kOdometryMinTravel) return Vec<2>(0.0, wrapped(u(2)));
  if (std::abs(m.rot1) > 0.5 * kPi) return Vec<2>(wrapped(m.rot1 - kPi), wrapped(m.rot2 + kPi));
  return Vec<2>(std::abs(m.rot1), wrapped(m.rot2));
}

/// (var_rot1, var_trans, var_rot2) of the step u (see the header comment).
inline Vec<3> odometry_variances(const OdometryDelta& u, const OdometryAlphas& a) {
  const Vec<2> r = odometry_noise_rotations(u);
  const double trans = std::hypot(u(0), u(1));
  const double r1 = r(0) * r(0), r2 = r(1) * r(1), t2 = trans * trans;
  return Vec<3>(a.alpha1 * r1 + a.alpha2 * t2, a.alpha3 * t2 + a.alpha4 * (r1 + r2),
                a.alpha1 * r2 + a.alpha2 * t2);
}

/// nav2's sampler: the pose reached from x when rot1, trans and rot2 of u are perturbed by their
/// noise. Three standard normals are drawn from rng, in the order rot1, trans, rot2. The alphas
/// must be valid (OdometryModel checks them once; this is the per-particle path).
inline Pose sample_odometry(const Pose& x, const OdometryDelta& u, const OdometryAlphas& a,
                            Rng& rng) {
  const Vec<3> sd = odometry_variances(u, a).cwiseSqrt();
  const Vec<3> z = rng.normal_vector<3>();
  OdometryMotion m = decompose_odometry(u);
  m.rot1 += sd(0) * z(0);
  m.trans += sd(1) * z(1);
  m.rot2 += sd(2) * z(2);
  return compose_motion(x, m);
}

/// The semi-synthetic protocol's odometry: the increment a robot would report when it truly
/// moved by true_increment, its rot1, trans and rot2 perturbed by the alpha noise (the same draw
/// as sample_odometry from the origin). Throws InvalidArgument for invalid alphas.
inline OdometryDelta perturb_odometry(const OdometryDelta& true_increment,
                                      const OdometryAlphas& alphas, Rng& rng) {
  alphas.validate();
  return sample_odometry(Pose::Zero(), true_increment, alphas, rng);
}

/// The odometry motion model (see the header comment). Immutable; cheap to copy.
class OdometryModel {
 public:
  using Control = OdometryDelta;
  static constexpr int StateDim = 3;
  static constexpr int ControlDim = 3;

  explicit OdometryModel(const OdometryAlphas& alphas = {},
                         const Vec<3>& floor_std = Vec<3>(0.005, 0.005, 0.002))
      : alphas_(alphas), floor_std_(floor_std) {
    alphas_.validate();
    require(floor_std_.allFinite() && (floor_std_.array() > 0).all(),
            "odometry floor_std: expected finite positive std devs (x [m], y [m], heading [rad]), "
            "got ({}, {}, {})",
            floor_std_(0), floor_std_(1), floor_std_(2));
  }

  const OdometryAlphas& alphas() const { return alphas_; }
  const Vec<3>& floor_std() const { return floor_std_; }
  /// Steps are odometry increments, not time: a step has unit length.
  double dt() const { return 1.0; }

  /// x ⊕ u: where the odometry says the robot went.
  Pose predict(const Pose& x, const Control& u) const { return compose(x, u); }

  /// d (pose reached) / d (rot1, trans, rot2) at the nominal motion of u from x.
  Mat3 motion_jacobian(const Pose& x, const Control& u) const {
    const OdometryMotion m = decompose_odometry(u);
    const double c = std::cos(x(2) + m.rot1), s = std::sin(x(2) + m.rot1);
    Mat3 j;
    j << -m.trans * s, c, 0.0,  //
        m.trans * c, s, 0.0,    //
        1.0, 0.0, 1.0;
    return j;
  }

  /// Sigma = J diag(var_rot1, var_trans, var_rot2) J^T + diag(floor_std^2): always SPD.
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    const Mat3 j = motion_jacobian(x, u);
    Mat3 sigma = j * odometry_variances(u, alphas_).asDiagonal() * j.transpose();
    sigma.diagonal() += floor_std_.cwiseAbs2();
    return sigma;
  }

  void predict_with_covariance(const Pose& x, const Control& u, Pose& f, Mat3& cov) const {
    f = predict(x, u);
    cov = process_covariance(x, u);
  }

  /// A draw of the exact (non-Gaussian) transition: sample_odometry, without the floor.
  Pose sample(const Pose& x, const Control& u, Rng& rng) const {
    return sample_odometry(x, u, alphas_, rng);
  }

 private:
  OdometryAlphas alphas_;
  Vec<3> floor_std_;
};

}  // namespace implicit::robot
