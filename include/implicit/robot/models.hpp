#pragma once
// What a filter needs from a robot: a motion model and a landmark sensor, as C++20 concepts.
//
// The particle filter (implicit/filter/particle_filter.hpp) is written against these concepts only,
// so a user localizes their own robot (a unicycle, a differential drive, ...) by writing two small
// classes; the filter, the proposals (bootstrap, implicit) and the data association stay untouched.
// UteModel and RangeBearingSensor are the library's models of the paper's vehicle and laser;
// UnicycleModel (a differential drive) and MountedRangeBearingSensor (any mounting offset and
// bearing convention) are ready-made alternatives.
//
//   struct MyRobot {                        // state (x, y, heading), control (v, omega)
//     double dt() const { return 0.1; }     // the nominal step length
//     MyRobot with_dt(double dt) const;     // optional: a step of another length
//     Pose predict(const Pose& x, const Control& u) const;      // mean of the next state
//     Mat3 process_covariance(const Pose& x, const Control& u) const;  // SPD covariance
//   };
//   static_assert(implicit::robot::MotionModel<Unicycle>);
//
// Common mistakes: returning a covariance that is only positive SEMI-definite (the implicit
// proposal needs its Cholesky factor: add a small state noise), and wrapping the heading inside
// predict() (leave it unwrapped; residuals are wrapped by the sensor).

#include <concepts>

#include "implicit/core/types.hpp"
#include "implicit/robot/mounted_sensor.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::robot {

/// A discrete-time Gaussian motion model x_n ~ N(predict(x_{n-1}, u_n), process_covariance(...)).
template <typename M>
concept MotionModel = requires(const M& m, const Pose& x, const Control& u) {
  { m.predict(x, u) } -> std::convertible_to<Pose>;
  { m.process_covariance(x, u) } -> std::convertible_to<Mat3>;
  { m.dt() } -> std::convertible_to<double>;
};

/// A motion model whose step length can change from step to step: with_dt(dt) is the model for
/// a step of length dt. The filters use it to step on the data's own time stamps; a model
/// without it can only run on data spaced by its dt().
template <typename M>
concept VariableStepMotionModel = MotionModel<M> && requires(const M& m, double dt) {
  { m.with_dt(dt) } -> std::convertible_to<M>;
};

/// A sensor measuring a 2-vector z = h(x, m) + v, v ~ N(0, noise_covariance()), of a point landmark
/// m. residual(predicted, z) returns predicted - z with any angle wrapped; jacobian_pose is dh/dx
/// (2x3).
template <typename S>
concept LandmarkSensor = requires(const S& s, const Pose& x, const Landmark& m,
                                  const Measurement& a) {
  { s.predict(x, m) } -> std::convertible_to<Measurement>;
  { s.residual(a, a) } -> std::convertible_to<Measurement>;
  { s.jacobian_pose(x, m) } -> std::convertible_to<Mat23>;
  { s.noise_covariance() } -> std::convertible_to<Mat2>;
};

/// A landmark sensor that also gives the second derivatives of h (one 3x3 Hessian per component).
/// With them the implicit proposal uses Newton's method with the exact Hessian; without them it
/// uses the Gauss-Newton Hessian (still exact weights, only a less efficient proposal).
template <typename S>
concept LandmarkSensorWithHessian = LandmarkSensor<S> &&
    requires(const S& s, const Pose& x, const Landmark& m, Mat3& h) {
  s.hessian_pose(x, m, h, h);
};

/// A landmark sensor whose first component is the Euclidean range |m - p| (unit gradient in the
/// position, none in the heading), available alone via range(x, m). Data association then rejects
/// a landmark when (range - z_0)^2 > gate * (Sigma2_00 + trace of the pose position covariance),
/// which is exact: d^2 >= e_0^2 / S_00 for any 2x2 SPD S, and S_00 is at most that bound.
template <typename S>
concept RangeFirstSensor = LandmarkSensor<S> &&
    requires(const S& s, const Pose& x, const Landmark& m) {
  { s.range(x, m) } -> std::convertible_to<double>;
};

/// A motion model that computes the mean and the covariance in one call (sharing work between
/// them); the proposals use it when present, predict() + process_covariance() otherwise.
template <typename M>
concept MotionModelWithCovariance = MotionModel<M> &&
    requires(const M& m, const Pose& x, const Control& u, Pose& f, Mat3& s) {
  m.predict_with_covariance(x, u, f, s);
};

/// A landmark sensor that computes predict() and jacobian_pose() in one call.
template <typename S>
concept LandmarkSensorWithFusedJacobian = LandmarkSensor<S> &&
    requires(const S& s, const Pose& x, const Landmark& m, Measurement& h, Mat23& j) {
  s.predict_with_jacobian(x, m, h, j);
};

static_assert(MotionModel<UteModel>);
static_assert(VariableStepMotionModel<UteModel>);
static_assert(VariableStepMotionModel<UnicycleModel>);
static_assert(LandmarkSensorWithHessian<MountedRangeBearingSensor>);
static_assert(LandmarkSensorWithFusedJacobian<MountedRangeBearingSensor>);
static_assert(MotionModelWithCovariance<UteModel>);
static_assert(LandmarkSensorWithFusedJacobian<RangeBearingSensor>);
static_assert(RangeFirstSensor<RangeBearingSensor>);
static_assert(LandmarkSensorWithHessian<RangeBearingSensor>);

}  // namespace implicit::robot
