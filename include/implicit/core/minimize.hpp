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
// The line step of the Newton loop that control's constrained path solver
// (control/path_solvers.hpp) still carries; minimize() and minimize_banded() run on
// newton_minimize. Goes when that solver does too.

/// Armijo backtracking from x along `step` (halving t): writes the accepted point to `trial` and
/// returns the accepted t, or 0 if no step decreased F. Non-finite trial values count as failures.
template <typename F, typename V>
double armijo_backtrack(const F& f, const V& x, const V& step, double value, double slope,
                        const MinimizeOptions& options, V& trial, int& evaluations) {
  double t = 1.0;
  for (int b = 0; b < options.max_backtracks; ++b, t *= 0.5) {
    trial = x + t * step;
    const double ft = f.evaluate(trial, nullptr, nullptr);
    ++evaluations;
    if (std::isfinite(ft) && ft <= value + options.armijo * t * slope) return t;
  }
  return 0.0;
}

/// Finiteness of a Hessian in either storage: dense Eigen or a structured type with all_finite().
template <typename H>
bool hessian_finite(const H& h) {
  if constexpr (requires { h.allFinite(); })
    return h.allFinite();
  else
    return h.all_finite();
}

enum class StepOutcome { kContinue, kStop, kNonFinite };

/// The part of a Newton iteration after the direction is known: steepest descent when `step` is
/// not a descent direction, Armijo backtracking, the move, and the convergence tests. Sets
/// r.status when the loop must end.
template <typename F, typename Result, typename V>
StepOutcome newton_line_step(const F& f, Result& r, V& step, V& trial,
                             const MinimizeOptions& options) {
  double slope = r.gradient.dot(step);
  if (!(slope < 0.0)) {
    step = -r.gradient;
    slope = -r.gradient.squaredNorm();
  }
  const double t = armijo_backtrack(f, r.x, step, r.value, slope, options, trial, r.evaluations);
  const double x_scale = 1.0 + r.x.cwiseAbs().maxCoeff();
  if (!(t > 0.0)) {
    // No decrease possible at machine precision: converged if the full step was already tiny.
    r.status = step.cwiseAbs().maxCoeff() <= options.step_tolerance * x_scale * 1e3
                   ? MinimizeStatus::kConverged
                   : MinimizeStatus::kLineSearchFailed;
    return StepOutcome::kStop;
  }
  const double step_size = t * step.cwiseAbs().maxCoeff();  // t is a power of 2: exact
  r.x = trial;
  r.value = f.evaluate(r.x, &r.gradient, &r.hessian);
  ++r.evaluations;
  if (!std::isfinite(r.value) || !r.gradient.allFinite() || !hessian_finite(r.hessian)) {
    r.status = MinimizeStatus::kNonFinite;
    return StepOutcome::kNonFinite;
  }
  if (step_size <= options.step_tolerance * x_scale) {
    ++r.iterations;
    r.status = MinimizeStatus::kConverged;
    return StepOutcome::kStop;
  }
  return StepOutcome::kContinue;
}
}  // namespace detail

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
