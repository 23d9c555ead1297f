#pragma once
// Minimising a dense target F: the Newton kernel (newton.hpp) with the dense factor.
//
// Implicit sampling starts at mu = argmin F. minimize() is newton_minimize<DenseFactor<N>>
// (damped Newton, Armijo backtracking, Levenberg damping of indefinite Hessians) with the
// gradient and relative-step stopping rules of MinimizeOptions, and its result in the Target's
// types (fixed-size Eigen, no allocation when N is fixed). It never throws on an algorithm
// outcome: that is a MinimizeStatus in the result (only a start point of the wrong dimension, a
// programming error, throws InvalidArgument). For long paths with block-tridiagonal Hessians see
// implicit/core/banded.hpp.
//
//   auto r = implicit::minimize(target, x0);
//   if (r.status != implicit::MinimizeStatus::kConverged) { ... }
//
// kNotPositiveDefinite: the iteration stopped (gradient or step below tolerance) at a point where
// the exact Hessian is not positive definite (a saddle or a flat direction), so it is not a
// Laplace centre. Non-finite F along a line search (outside the support, NaN) counts as a failed
// step and the step is halved.

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/minimize_options.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/target.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

template <int N>
struct MinimizeResult {
  Vec<N> x;                                                 ///< the minimiser (or the last iterate)
  double value = std::numeric_limits<double>::quiet_NaN();  ///< F(x)
  Vec<N> gradient;                                          ///< grad F(x)
  Mat<N> hessian;  ///< Hessian of F at x (exact, possibly indefinite)
  int iterations = 0;
  int evaluations = 0;
  MinimizeStatus status = MinimizeStatus::kMaxIterations;
  bool converged() const { return status == MinimizeStatus::kConverged; }
};

namespace detail {
/// The factor of minimize(): Eigen's LLT, but the written-out 3x3 Cholesky for N = 3 (poses): it
/// does not take the logs of log det L at every iteration, which cost as much as the rest of a
/// 3-D Newton step.
template <int N>
using MinimizeFactor = std::conditional_t<N == 3, SmallFactor<3>, DenseFactor<N>>;

/// The status of minimize() and minimize_banded() from the kernel's: a point where the exact
/// Hessian is not SPD is not a minimum, even when a damped matrix factored there (the kernel's
/// kNotPositiveDefinite means that nothing factored at all).
template <typename Minimum>
MinimizeStatus minimum_status(const Minimum& k) {
  if (k.status == MinimizeStatus::kConverged && !k.exact_factor)
    return MinimizeStatus::kNotPositiveDefinite;
  return k.status;
}
}  // namespace detail

/// Minimises `f` from x0: newton_minimize with the dense factor and the stopping rules of
/// `options` (gradient, relative step). Never throws on algorithm failure; see `status`.
template <Target T>
MinimizeResult<T::Dim> minimize(const T& f, const typename T::Vector& x0,
                                const MinimizeOptions& options = {}) {
  constexpr int N = T::Dim;
  const int n = f.dim();
  // A start point of the wrong size is bad input (evaluating F there would read out of bounds).
  require(x0.size() == n, "minimize: expected a start point of dimension {}, got {}", n, x0.size());
  auto k = newton_minimize<detail::MinimizeFactor<N>>(f, x0, NewtonOptions(options));
  MinimizeResult<N> r;
  r.status = detail::minimum_status(k);
  r.x = std::move(k.x);
  r.value = k.value;
  r.gradient = std::move(k.gradient);
  r.hessian = std::move(k.hessian);
  r.iterations = k.iterations;
  r.evaluations = k.evaluations;
  return r;
}

}  // namespace implicit
