#include "implicit/da/path_objective.hpp"

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"

namespace implicit::da {

PathTerms::PathTerms(const Problem& p, const Eigen::MatrixXd& q, const Eigen::VectorXd& y_in)
    : steps(p.steps_per_observation), y(y_in) {
  const int n = p.dim(), m = p.obs_dim();
  require_spd(q, n, "implicit path: model noise Q");
  require(y.size() == m && y.allFinite(),
          "implicit path: expected a finite observation of size {} (the rows of H), got size {}", m,
          y.size());
  const Eigen::LLT<Eigen::MatrixXd> q_llt(q);
  q_inv = q_llt.solve(Eigen::MatrixXd::Identity(n, n));
  r_lower = p.R.llt().matrixL();
  const double log_det_lq = q_llt.matrixLLT().diagonal().array().log().sum();
  const double log_det_lr = r_lower.diagonal().array().log().sum();
  // K independent N(0, Q) noises and one N(0, R) error: a Gaussian of dimension nK + m whose
  // Cholesky factor is blockdiag(L_Q, ..., L_Q, L_R).
  log_norm = gaussian_log_normaliser(n * steps + m, steps * log_det_lq + log_det_lr);
}

void prepare_scratch(const Problem& p, PathObjective::Scratch& s) {
  const int n = p.dim(), m = p.obs_dim(), k = p.steps_per_observation;
  p.model->prepare(s.forecast);
  s.step_jacobian.assign(static_cast<std::size_t>(k), Eigen::MatrixXd(n, n));
  s.state.resize(n);
  s.residual.resize(m);
  s.q_w.resize(n);
  s.sensitivity.resize(n, n);
  s.product.resize(n, n);
  s.hg.resize(m, n * k);
}

NewtonOptions path_newton_options() {
  NewtonOptions options;
  options.decrement_tolerance = 1e-8;
  return options;
}

void PathObjective::end_state(const Vector& w, Eigen::VectorXd& x) const {
  const Problem& p = *p_;
  const int n = p.dim();
  x = *parent_;
  for (int i = 0; i < t_->steps; ++i) {
    p.model->forecast(x, s_->forecast);
    x += w.segment(i * n, n);
  }
}

double PathObjective::evaluate(const Vector& w, Vector* grad, Hessian* hess) const {
  const Problem& p = *p_;
  const PathTerms& t = *t_;
  Scratch& s = *s_;
  const int n = p.dim(), k = t.steps;
  const bool derivatives = grad != nullptr || hess != nullptr;
  // Forward along the path; J_i, the derivative of interval i at its start x_{i-1}, is needed
  // for i >= 2 only (x_0 is the parent, not a variable).
  s.state = *parent_;
  for (int i = 0; i < k; ++i) {
    if (derivatives && i > 0)
      p.model->forecast_jacobian(s.state, s.step_jacobian[static_cast<std::size_t>(i)], s.forecast);
    else
      p.model->forecast(s.state, s.forecast);
    s.state += w.segment(i * n, n);
  }
  if (!s.state.allFinite()) return kInfinity;
  s.residual = t.y;  // whitened: L_R^-1 (y - H x_K)
  s.residual.noalias() -= p.H * s.state;
  t.r_lower.triangularView<Eigen::Lower>().solveInPlace(s.residual);
  double prior = 0.0;
  for (int i = 0; i < k; ++i) {
    s.q_w.noalias() = t.q_inv * w.segment(i * n, n);
    prior += w.segment(i * n, n).dot(s.q_w);
    if (grad != nullptr) grad->segment(i * n, n) = s.q_w;
  }
  if (derivatives) {
    // Backwards: dx_K/dw_K = I, dx_K/dw_i = (dx_K/dw_{i+1}) J_{i+1}; each block of
    // L_R^-1 H G is L_R^-1 H times it.
    s.sensitivity.setIdentity();
    for (int i = k - 1; i >= 0; --i) {
      auto block = s.hg.middleCols(i * n, n);
      block.noalias() = p.H * s.sensitivity;
      t.r_lower.triangularView<Eigen::Lower>().solveInPlace(block);
      if (i == 0) break;
      s.product.noalias() = s.sensitivity * s.step_jacobian[static_cast<std::size_t>(i)];
      s.sensitivity.swap(s.product);
    }
    if (grad != nullptr) grad->noalias() -= s.hg.transpose() * s.residual;
    if (hess != nullptr) {
      hess->setZero(n * k, n * k);
      for (int i = 0; i < k; ++i) hess->block(i * n, i * n, n, n) = t.q_inv;
      hess->noalias() += s.hg.transpose() * s.hg;
    }
  }
  return 0.5 * (prior + s.residual.squaredNorm()) + t.log_norm;
}

}  // namespace implicit::da
