#pragma once
// Minimising F: damped Newton with Armijo backtracking and Levenberg damping.
//
// Implicit sampling starts at mu = argmin F. This minimiser is written for small dense problems
// evaluated once per particle (fixed-size Eigen types, no allocation when N is fixed), so it
// never throws on an algorithm outcome: that is a MinimizeStatus in the result (only a start
// point of the wrong dimension, a programming error, throws InvalidArgument). For long paths with
// block-tridiagonal Hessians see implicit/core/banded.hpp.
//
//   auto r = implicit::minimize(target, x0);
//   if (r.status != implicit::MinimizeStatus::kConverged) { ... }
//
// Indefinite Hessians: the Newton system uses H + lambda I with the smallest lambda (grown by
// factors of 10 from 1e-8 * max|H_ii|) for which the Cholesky factorisation succeeds. Non-finite
// F along a line search (outside the support, NaN) counts as a failed step and the step is halved.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "implicit/core/minimize_options.hpp"
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
inline bool all_finite(double v) { return std::isfinite(v); }
template <typename Derived>
inline bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}
}  // namespace detail

namespace detail {
/// Armijo backtracking from x along `step` (halving t): writes the accepted point to `trial` and
/// returns the accepted t, or 0 if no step decreased F. Non-finite trial values count as failures.
/// Shared by the dense and the banded Newton loops.
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

/// The part of a Newton iteration after the direction is known, shared by the dense and banded
/// loops so that both apply the same safeguards: steepest descent when `step` is not a descent
/// direction, Armijo backtracking, the move, and the convergence tests. Sets r.status when the
/// loop must end.
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

/// Minimises `f` from x0 by damped Newton. Never throws on algorithm failure; see `status`.
template <Target T>
MinimizeResult<T::Dim> minimize(const T& f, const typename T::Vector& x0,
                                const MinimizeOptions& options = {}) {
  constexpr int N = T::Dim;
  using V = Vec<N>;
  using M = Mat<N>;
  const int n = f.dim();
  // A start point of the wrong size is bad input (evaluating F there would read out of bounds).
  require(x0.size() == n, "minimize: expected a start point of dimension {}, got {}", n, x0.size());
  MinimizeResult<N> r;
  r.x = x0;
  r.gradient.resize(n);
  r.hessian.resize(n, n);
  r.value = f.evaluate(r.x, &r.gradient, &r.hessian);
  r.evaluations = 1;
  if (!detail::all_finite(r.value) || !r.gradient.allFinite() || !r.hessian.allFinite()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  Eigen::LLT<M> llt(n);
  M damped = M::Zero(n, n);
  V step = V::Zero(n);
  V trial = V::Zero(n);
  r.status = MinimizeStatus::kMaxIterations;
  for (r.iterations = 0; r.iterations < options.max_iterations; ++r.iterations) {
    if (r.gradient.cwiseAbs().maxCoeff() <= options.gradient_tolerance) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
    // Newton direction, Levenberg-damped until the factorisation succeeds.
    llt.compute(r.hessian);
    if (llt.info() != Eigen::Success) {
      const double scale = std::max(1.0, r.hessian.diagonal().cwiseAbs().maxCoeff());
      double lambda = 1e-8 * scale;
      for (int k = 0; k < 40; ++k, lambda *= 10.0) {
        damped = r.hessian;
        damped.diagonal().array() += lambda;
        llt.compute(damped);
        if (llt.info() == Eigen::Success) break;
      }
    }
    if (llt.info() == Eigen::Success) {
      step = -llt.solve(r.gradient);
    } else {
      step = -r.gradient;
    }
    const auto outcome = detail::newton_line_step(f, r, step, trial, options);
    if (outcome == detail::StepOutcome::kNonFinite) return r;
    if (outcome == detail::StepOutcome::kStop) break;
  }
  if (r.status == MinimizeStatus::kConverged) {
    llt.compute(r.hessian);
    if (llt.info() != Eigen::Success) r.status = MinimizeStatus::kNotPositiveDefinite;
  }
  return r;
}

}  // namespace implicit
