#pragma once
// The seam between a robot's sensors and the filters: one observation model per WHOLE
// observation (a laser scan, a set of detections), and a motion model with a control type of
// its own. The particle filters (filter/monte_carlo_localization.hpp) and their proposals are
// written against these concepts only, so a new sensor is one file that models them.
//
//   struct MySensor {
//     using Observation = MyScan;          // what the data gives per update
//     using Prepared = MyBeams;            // what every particle reads: computed once per update
//     Prepared prepare(const MyScan& z, std::string_view where) const;   // validates z
//     double log_likelihood(const Prepared& z, const Pose& x) const;     // log p(z | x)
//     // for the implicit proposal (optional):
//     bool differentiable() const;                        // false: the proposal refuses it
//     std::string_view why_not_differentiable() const;
//     double negative_log_likelihood(const Prepared& z, const Pose& x, Vec<3>* gradient,
//                                    Mat3* gauss_newton) const;   // ADDS to both (may be null)
//   };
//
// log_likelihood serves the bootstrap proposal, global starts and the lost signal;
// negative_log_likelihood is the observation's part of the implicit proposal's objective
// F(x) = 1/2 |x - f|^2_{Sigma1^-1} + const - log p(z | x) (filter/pose_objective.hpp). Its
// Gauss-Newton matrix must be positive semi-definite: with the motion prior, F's matrix is then
// positive definite and the implicit weights are exact.
//
// An observation model may also count, per pose, what it used and what it dropped (landmark
// detections outside the association gate): log_likelihood(z, x, counts)
// (CountingObservationModel).
//
// And it may check an observation against the filter's prediction before any particle reads it
// (PredictionGatedObservationModel): parts that no pose the filter considers possible could
// produce (a labelled detection 500 m from a landmark 5 m away) are left out of the step and
// counted, instead of moving every particle.
//
// A motion model gives the Gaussian transition x_n ~ N(predict(x, u), process_covariance(x, u))
// for its own Control type (a Vec<2> speed and steering for the Ute, an odometry increment for
// OdometryModel); a model without a `Control` member type takes robot::Control.

#include <concepts>
#include <string_view>
#include <type_traits>

#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

namespace detail {
template <typename M>
struct ControlOf {
  using type = Control;
};
template <typename M>
requires requires { typename M::Control; }
struct ControlOf<M> {
  using type = typename M::Control;
};
}  // namespace detail

/// The control type of motion model M: M::Control, else robot::Control.
template <typename M>
using ControlOf = typename detail::ControlOf<M>::type;

/// A Gaussian pose transition with its own control type.
template <typename M>
concept PoseMotionModel = requires(const M& m, const Pose& x, const ControlOf<M>& u) {
  { m.predict(x, u) } -> std::convertible_to<Pose>;
  { m.process_covariance(x, u) } -> std::convertible_to<Mat3>;
};

/// A pose motion model that computes the mean and the covariance in one call.
template <typename M>
concept PoseMotionModelWithCovariance = PoseMotionModel<M> &&
    requires(const M& m, const Pose& x, const ControlOf<M>& u, Pose& f, Mat3& s) {
  m.predict_with_covariance(x, u, f, s);
};

/// An observation model: log p(whole observation | pose).
template <typename O>
concept ObservationModel = requires(const O& o, const typename O::Observation& z,
                                    const typename O::Prepared& p, const Pose& x,
                                    std::string_view where) {
  { o.prepare(z, where) } -> std::convertible_to<typename O::Prepared>;
  { o.log_likelihood(p, x) } -> std::convertible_to<double>;
};

/// An observation model that the implicit proposal can use: -log p with its gradient and a
/// positive semi-definite Gauss-Newton matrix.
template <typename O>
concept DifferentiableObservationModel = ObservationModel<O> &&
    requires(const O& o, const typename O::Prepared& p, const Pose& x, Vec<3>* g, Mat3* h) {
  { o.negative_log_likelihood(p, x, g, h) } -> std::convertible_to<double>;
  { o.differentiable() } -> std::convertible_to<bool>;
  { o.why_not_differentiable() } -> std::convertible_to<std::string_view>;
};

/// What an observation model may count per pose: the parts of the observation it used and the
/// ones it dropped (landmark detections outside the association gate).
struct ObservationCounts {
  int used = 0;
  int dropped = 0;
};

/// An observation model that counts them: log_likelihood(z, x, counts) is log_likelihood(z, x)
/// and ADDS to counts.used and counts.dropped. The filters then report the weighted mean counts.
template <typename O>
concept CountingObservationModel = ObservationModel<O> &&
    requires(const O& o, const typename O::Prepared& p, const Pose& x, ObservationCounts& c) {
  { o.log_likelihood(p, x, c) } -> std::convertible_to<double>;
};

/// An observation model that gates parts of an observation against the filter's predicted pose
/// distribution (mean, covariance) at a step: gate(z, mean, cov, kept) returns how many parts it
/// left out; when that is not 0, `kept` holds the others and the step uses Observation(kept).
/// gate_needed(z) says whether z has anything to gate (the filter skips the prediction if not).
template <typename O>
concept PredictionGatedObservationModel = ObservationModel<O> &&
    requires(const O& o, const typename O::Observation& z, const Pose& mean, const Mat3& cov,
             typename O::GateKept& kept) {
  { o.gate(z, mean, cov, kept) } -> std::convertible_to<int>;
  { o.gate_needed(z) } -> std::convertible_to<bool>;
} && std::constructible_from<typename O::Observation, typename O::GateKept&>;

}  // namespace implicit::robot
