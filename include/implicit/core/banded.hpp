#pragma once
// Minimising banded targets: the "banded path" of the Newton kernel.
//
// A path target (n blocks of B variables, coupled only between neighbours) has a block-
// tridiagonal Hessian (block_tridiagonal.hpp), factored in O(n B^3). minimize_banded() is
// newton_minimize (newton.hpp) with the banded factor BandedFactor<B>, with the default stopping
// rules of minimize(); its result keeps the Cholesky factor of the exact Hessian at the end.
//
//   auto r = implicit::minimize_banded(path_target, y0);
//   if (r.converged()) { /* r.factor.upper_solve_in_place(xi), r.factor.log_det_L() */ }

#include <concepts>
#include <limits>

#include <Eigen/Core>

#include "implicit/core/block_tridiagonal.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

/// A target whose variables are n blocks of size Block and whose Hessian is block tridiagonal:
///
///   static constexpr int Block;
///   int num_blocks() const;
///   double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* grad,
///                   BlockTridiagonal<Block>* hess) const;   // grad/hess may be null
///
/// Return +infinity outside the support.
template <typename T>
concept BandedTarget = requires(const T& t, const Eigen::VectorXd& y, Eigen::VectorXd* g,
                                BlockTridiagonal<T::Block>* h) {
  { T::Block } -> std::convertible_to<int>;
  { t.num_blocks() } -> std::convertible_to<int>;
  { t.evaluate(y, g, h) } -> std::convertible_to<double>;
};

template <int B>
struct BandedMinimizeResult {
  Eigen::VectorXd x;  ///< the minimiser (or the last iterate), n B entries
  double value = std::numeric_limits<double>::quiet_NaN();  ///< F(x)
  Eigen::VectorXd gradient;
  BlockTridiagonal<B> hessian;         ///< exact Hessian at x (possibly indefinite)
  BlockTridiagonalCholesky<B> factor;  ///< Cholesky of `hessian` (ok() if SPD)
  int iterations = 0;
  int evaluations = 0;
  MinimizeStatus status = MinimizeStatus::kMaxIterations;
  bool converged() const { return status == MinimizeStatus::kConverged; }
};

/// Damped Newton (Levenberg damping + Armijo backtracking, as minimize()) for a banded target.
/// O(n B^3) per iteration. Never throws on algorithm failure; see `status`.
template <BandedTarget T>
BandedMinimizeResult<T::Block> minimize_banded(const T& f, const Eigen::VectorXd& x0,
                                               const MinimizeOptions& options = {}) {
  constexpr int B = T::Block;
  const int nb = f.num_blocks();
  BandedMinimizeResult<B> r;
  r.x = x0;
  r.gradient.resize(nb * B);
  r.hessian.resize(nb);
  if (x0.size() != nb * B || nb <= 0) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  r.value = f.evaluate(r.x, &r.gradient, &r.hessian);
  r.evaluations = 1;
  if (!std::isfinite(r.value) || !r.gradient.allFinite() || !r.hessian.all_finite()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  BlockTridiagonal<B> damped;
  Eigen::VectorXd step(nb * B), trial(nb * B);
  r.status = MinimizeStatus::kMaxIterations;
  for (r.iterations = 0; r.iterations < options.max_iterations; ++r.iterations) {
    if (r.gradient.cwiseAbs().maxCoeff() <= options.gradient_tolerance) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
    bool factored = r.factor.compute(r.hessian);
    if (!factored) {
      double scale = 1.0;
      for (const auto& d : r.hessian.diagonal)
        scale = std::max(scale, d.diagonal().cwiseAbs().maxCoeff());
      double lambda = 1e-8 * scale;
      for (int k = 0; k < 40 && !factored; ++k, lambda *= 10.0) {
        damped = r.hessian;
        damped.add_to_diagonal(lambda);
        factored = r.factor.compute(damped);
      }
    }
    step = -r.gradient;
    if (factored) r.factor.solve_in_place(step);
    const auto outcome = detail::newton_line_step(f, r, step, trial, options);
    if (outcome == detail::StepOutcome::kNonFinite) return r;
    if (outcome == detail::StepOutcome::kStop) break;
  }
  // Leave `factor` as the Cholesky of the exact Hessian at the final point.
  if (!r.factor.compute(r.hessian) && r.status == MinimizeStatus::kConverged)
    r.status = MinimizeStatus::kNotPositiveDefinite;
  return r;
}

}  // namespace implicit
