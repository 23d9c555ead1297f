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
#include <utility>

#include <Eigen/Core>

#include "implicit/core/block_tridiagonal.hpp"
#include "implicit/core/gaussian_factor.hpp"
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

/// minimize() for a banded target: newton_minimize<BandedFactor<B>> with the stopping rules of
/// `options`, O(n B^3) per iteration. `factor` is the Cholesky of the exact Hessian at the end
/// (not ok() where that is not SPD, and then a converged run reports kNotPositiveDefinite). A start
/// point of the wrong size is kNonFinite. Never throws on algorithm failure; see `status`.
template <BandedTarget T>
BandedMinimizeResult<T::Block> minimize_banded(const T& f, const Eigen::VectorXd& x0,
                                               const MinimizeOptions& options = {}) {
  constexpr int B = T::Block;
  const int nb = f.num_blocks();
  BandedMinimizeResult<B> r;
  if (x0.size() != nb * B || nb <= 0) {
    r.x = x0;
    r.gradient.resize(nb * B);
    r.hessian.resize(nb);
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  auto k = newton_minimize<BandedFactor<B>>(f, x0, NewtonOptions(options));
  r.status = detail::minimum_status(k);
  r.x = std::move(k.x);
  r.value = k.value;
  r.gradient = std::move(k.gradient);
  r.hessian = std::move(k.hessian);
  // The kernel's factor may be of a damped Hessian; the result promises the exact one's.
  if (k.exact_factor)
    r.factor = std::move(k.factor);
  else
    r.factor.compute(r.hessian);
  r.iterations = k.iterations;
  r.evaluations = k.evaluations;
  return r;
}

}  // namespace implicit
