#pragma once
// The implicit particle filter's objective when an observation follows K > 1 noisy model
// intervals (Problem::steps_per_observation; docs/specification.md, "Data assimilation"). From
// a member x', the K interval noises w = (w_1, ..., w_K) of the path
//
//   x_0 = x',   x_i = M(x_{i-1}) + w_i   (i = 1..K),
//
// are the variables, and
//
//   F(w) = 1/2 sum_i |w_i|^2_{Q^-1} + 1/2 |y - H x_K(w)|^2_{R^-1}
//          + K/2 log det 2 pi Q + 1/2 log det 2 pi R,
//
// so that the integral of exp(-F) over w is p(y | x'). For one interval (K = 1) x_1 is linear in
// w and the implicit sample is the optimal proposal's; for K > 1, x_K depends on w_1..w_{K-1}
// through the nonlinear model, p(w | x', y) is not Gaussian, and implicit sampling (Newton on F,
// the linear or random map, the exact weight) differs from any Gaussian "optimal proposal".
//
//   implicit::da::PathTerms t(problem, q, y);     // per cycle, shared by the members
//   implicit::da::PathObjective::Scratch s;        // per member slot, reused
//   implicit::da::prepare_scratch(problem, s);
//   implicit::da::PathObjective f(problem, t, x_parent, s);
//   const double value = f.evaluate(w, &grad, &hess);
//   f.end_state(w, x);                             // x_K(w): the member after the cycle
//
// The Hessian returned is the Gauss-Newton one, blockdiag(Q^-1) + G^T H^T R^-1 H G with
// G = dx_K/dw = [J_K...J_2, ..., J_K, I] (J_i = dM/dx at x_{i-1}): the model's second
// derivative is left out, so it is SPD, and the implicit weights stay exact for any SPD factor.

#include <vector>

#include <Eigen/Core>

#include "implicit/core/newton.hpp"
#include "implicit/da/model.hpp"

namespace implicit::da {

/// What every member's F shares in one cycle.
struct PathTerms {
  /// Q is the noise covariance of one interval (the problem's, or the jitter's on a
  /// deterministic model); y the cycle's observation.
  PathTerms(const Problem& p, const Eigen::MatrixXd& q, const Eigen::VectorXd& y);

  int steps = 1;            ///< K
  Eigen::MatrixXd q_inv;    ///< Q^-1
  Eigen::MatrixXd r_lower;  ///< L_R, L_R L_R^T = R
  Eigen::VectorXd y;
  double log_norm = 0.0;  ///< K/2 log det 2 pi Q + 1/2 log det 2 pi R
};

class PathObjective {
 public:
  using Vector = Eigen::VectorXd;
  using Hessian = Eigen::MatrixXd;

  /// Per-member storage, sized by prepare_scratch and reused every cycle.
  struct Scratch {
    ForecastWorkspace forecast;
    std::vector<Eigen::MatrixXd> step_jacobian;  ///< J_1..J_K of the last evaluation
    Eigen::VectorXd state, residual, q_w;
    Eigen::MatrixXd sensitivity, product, hg;  ///< dx_K/dw_i (n x n), L_R^-1 H G (p x nK)
  };

  /// p, t, parent and scratch must outlive the objective.
  PathObjective(const Problem& p, const PathTerms& t, const Eigen::VectorXd& parent,
                Scratch& scratch)
      : p_(&p), t_(&t), parent_(&parent), s_(&scratch) {}

  /// F(w) for w of size nK; with grad / hess also its gradient and the Gauss-Newton Hessian.
  /// +inf when the path leaves the finite numbers.
  double evaluate(const Vector& w, Vector* grad, Hessian* hess) const;
  /// x = x_K(w), the end of the path.
  void end_state(const Vector& w, Eigen::VectorXd& x) const;

 private:
  const Problem* p_;
  const PathTerms* t_;
  const Eigen::VectorXd* parent_;
  Scratch* s_;
};

/// Sizes a scratch for problem p.
void prepare_scratch(const Problem& p, PathObjective::Scratch& s);

/// The implicit filter's Newton options for a path: the defaults, and a stop once the predicted
/// decrease of F, half g^T H^-1 g, is below 5e-9. The Gauss-Newton Hessian makes the last
/// iterations linear, not quadratic, so the default gradient tolerance alone takes about twice
/// the iterations for a minimum that moves F by less than that; the weight is exact at any mode
/// (bench_da, PathMove/decrement against PathMove/gradient).
NewtonOptions path_newton_options();

}  // namespace implicit::da
