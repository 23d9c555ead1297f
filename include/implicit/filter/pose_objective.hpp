#pragma once
// The one pose objective of the implicit proposal for any differentiable observation model
// (robot/observation_model.hpp): a Gaussian motion prior plus the observation's terms,
//
//   F(x) = 1/2 |x - f|^2_{Sigma1^-1} + constant - log p(z | x),
//
// with f and Sigma1 the particle's prediction and process covariance and constant =
// 1/2 log det(2 pi Sigma1), kept because different particles have different F (their weights
// compare F across particles). Newton (core/newton.hpp) minimises it with the Gauss-Newton
// matrix prior information + the model's positive semi-definite matrix, which is positive
// definite; the implicit weights are exact with it.
//
//   PoseObjective<LikelihoodFieldModel> f;
//   f.reset(model, beams, prediction, prior_information, constant);
//   PoseMinimum r = newton_minimize<SmallFactor<3>>(f, prediction, scan_newton_options());

#include "implicit/core/newton.hpp"
#include "implicit/robot/observation_model.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::filter {

template <robot::DifferentiableObservationModel Observation>
class PoseObjective {
 public:
  using Prepared = typename Observation::Prepared;

  void reset(const Observation& model, const Prepared& z, const robot::Pose& prediction,
             const robot::Mat3& prior_information, double constant) {
    model_ = &model;
    z_ = &z;
    prediction_ = prediction;
    prior_information_ = prior_information;
    constant_ = constant;
  }

  double constant() const { return constant_; }
  const robot::Pose& prediction() const { return prediction_; }

  /// F(x); optionally its gradient and the Gauss-Newton matrix (as `hessian` and as
  /// `gauss_newton`: the model gives no exact second derivatives).
  double evaluate(const robot::Pose& x, Vec<3>* gradient = nullptr, robot::Mat3* hessian = nullptr,
                  robot::Mat3* gauss_newton = nullptr) const {
    const Vec<3> d = x - prediction_;
    const Vec<3> pd = prior_information_ * d;
    double value = constant_ + 0.5 * d.dot(pd);
    robot::Mat3 gn;
    const bool matrix = hessian != nullptr || gauss_newton != nullptr;
    if (gradient) *gradient = pd;
    if (matrix) gn = prior_information_;
    value += model_->negative_log_likelihood(*z_, x, gradient, matrix ? &gn : nullptr);
    if (hessian) *hessian = gn;
    if (gauss_newton) *gauss_newton = gn;
    return value;
  }

 private:
  const Observation* model_ = nullptr;
  const Prepared* z_ = nullptr;
  robot::Pose prediction_ = robot::Pose::Zero();
  robot::Mat3 prior_information_ = robot::Mat3::Identity();
  double constant_ = 0.0;
};

/// Newton's stopping rules for pose objectives whose matrix is Gauss-Newton (convergence is
/// linear, not quadratic); src/filter/pose_objective.cpp gives them and why. Where Newton stops
/// does not bias the filter: the weights are exact for any centre and any SPD matrix; a poorer
/// centre only lowers the effective sample size.
NewtonOptions scan_newton_options();

}  // namespace implicit::filter
