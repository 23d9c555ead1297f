#pragma once
// The one minimiser of implicit sampling: damped Newton, generic over the Gaussian factor.
//
// Implicit sampling starts at mu = argmin F and samples with the factor of the Hessian there.
// newton_minimize() is written once for every such problem and is generic over the factor
// (gaussian_factor.hpp): dense targets (DenseFactor<N>), the 3x3 and 5x5 pose objectives of
// implicit MCL and SLAM (SmallFactor<N>, no heap), banded paths (BandedFactor<B>), and path
// problems with hard walls (equality constraints). A fast path is a specialised objective or
// factor, never a copy of this loop.
//
//   auto r = implicit::newton_minimize<implicit::SmallFactor<3>>(objective, x0, options);
//   if (r.factor_ok) { /* sample x = r.x + L^{-T} xi with r.factor, phi = r.value */ }
//
// The objective provides, for the factor's Vector and Hessian types,
//   double evaluate(const Vector& x, Vector* grad, Hessian* hess) const;  // may be null
// and, for HessianFallback::kGaussNewton, also
//   double evaluate(const Vector& x, Vector* grad, Hessian* hess, Hessian* gauss_newton) const;
// Return +infinity (or NaN) outside the support: a trial step there counts as failed.
//
// Each iteration: factor the exact Hessian; if it is not SPD, the Gauss-Newton Hessian (always
// SPD for least squares) or H + lambda I with lambda grown by 10 from 1e-8 max|H_ii|; if nothing
// factors, steepest descent. Stopping rules (NewtonOptions): gradient, Newton decrement
// g^T H^-1 g, step size, and `final_step` (a full exact step this small ends it: convergence is
// quadratic). Armijo backtracking; the first trial is evaluated with derivatives (usually
// accepted, so one evaluation per iteration), the backtracks values only, and both the change
// of F and the predicted decrease at round-off end the search. With equality constraints
// C^T x = e, the start is moved onto them by the smallest H-norm correction and every step is
// the range-space Newton step (Z = H^-1 C, S = C^T Z); `multipliers` returns nu with
// grad F + C nu = 0. Never throws on an algorithm outcome: see `status`.

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>
#include <type_traits>
#include <utility>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/minimize_options.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

/// What to factor when the exact Hessian is not positive definite.
enum class HessianFallback { kLevenberg, kGaussNewton };

/// MinimizeOptions (iterations, gradient and step tolerances, Armijo constant, backtracks) plus
/// the stopping rules and fallback that the structured callers choose.
struct NewtonOptions : MinimizeOptions {
  bool relative_step_tolerance = true;  ///< false: max|step| <= step_tolerance
  double decrement_tolerance = 0.0;     ///< stop when g^T H^-1 g < this (0: rule off)
  double final_step = 0.0;  ///< stop after a full exact step with max|step| <= this (0: off)
  HessianFallback fallback = HessianFallback::kLevenberg;
  /// false: no Levenberg damping and no steepest descent; a point where neither the exact nor the
  /// Gauss-Newton Hessian factors ends the minimisation (kNotPositiveDefinite), for callers with a
  /// better plan than a damped minimum (implicit MCL samples its prior instead).
  bool damping = true;

  NewtonOptions() = default;
  explicit NewtonOptions(const MinimizeOptions& base) : MinimizeOptions(base) {}
};

/// C^T x = e: one column of C per constraint.
template <int N>
struct EqualityConstraints {
  Eigen::Matrix<double, N, Eigen::Dynamic> C;
  Eigen::VectorXd e;
  int size() const { return static_cast<int>(C.cols()); }
};

template <FactorModel Factor>
struct NewtonMinimum {
  using Vector = typename Factor::Vector;
  using Hessian = typename Factor::Hessian;
  Vector x;                                                 ///< the minimiser (or last iterate)
  double value = std::numeric_limits<double>::quiet_NaN();  ///< F(x)
  Vector gradient;                                          ///< grad F(x)
  Hessian hessian;                                          ///< exact Hessian at x
  Factor factor;                ///< factor of the Hessian used at x (see exact_factor)
  bool factor_ok = false;       ///< `factor` holds an SPD factorisation at x
  bool exact_factor = true;     ///< false: Gauss-Newton or damped (the weights stay exact)
  Eigen::VectorXd multipliers;  ///< equality-constraint multipliers nu
  int iterations = 0;           ///< accepted steps
  int evaluations = 0;          ///< evaluations of F (with or without derivatives)
  /// kNotPositiveDefinite here means that no SPD matrix could be factored at x.
  MinimizeStatus status = MinimizeStatus::kMaxIterations;
  bool converged() const { return status == MinimizeStatus::kConverged; }
};

namespace detail {

template <typename F, typename V, typename H>
concept HasGaussNewton = requires(const F& f, const V& x, V* g, H* h) {
  { f.evaluate(x, g, h, h) } -> std::convertible_to<double>;
};

/// Newton-loop state: the current point with its derivatives, and a trial point.
template <FactorModel Factor, bool kGaussNewton>
struct NewtonWork {
  using V = typename Factor::Vector;
  using H = typename Factor::Hessian;
  V trial, trial_gradient, step;
  H trial_hessian, gauss_newton, trial_gauss_newton, damped;

  template <typename F>
  double evaluate(const F& f, const V& x, V& g, H& h, H& gn) const {
    if constexpr (kGaussNewton)
      return f.evaluate(x, &g, &h, &gn);
    else
      return f.evaluate(x, &g, &h);
  }
};

template <typename H>
void size_hessian(H& h, Eigen::Index n) {
  if constexpr (requires { h.subdiagonal; })  // BlockTridiagonal<B>: n / B blocks
    h.resize(static_cast<int>(n / std::decay_t<decltype(h.diagonal[0])>::RowsAtCompileTime));
  else
    h.resize(n, n);
}

template <typename V>
bool finite(const V& v) {
  if constexpr (requires { v.allFinite(); })
    return v.allFinite();
  else
    return v.all_finite();
}

/// Factors the Hessian at the current point: exact, else Gauss-Newton or Levenberg-damped.
/// Returns false when nothing factors; `exact` says which matrix the factor holds.
template <typename Factor, typename H>
bool factor_with_fallback(Factor& factor, const H& exact_h, const H* gauss_newton, H& damped,
                          bool& exact, bool damping = true) {
  exact = factor.compute(exact_h);
  if (exact) return true;
  if (gauss_newton != nullptr && factor.compute(*gauss_newton)) return true;
  if (!damping) return false;
  double lambda = 1e-8 * std::max(1.0, Factor::diagonal_scale(exact_h));
  for (int k = 0; k < 40; ++k, lambda *= 10.0) {
    damped = exact_h;
    Factor::add_to_diagonal(damped, lambda);
    if (factor.compute(damped)) return true;
  }
  return false;
}

/// Range-space projection with equality constraints: Z = H^-1 C, S = C^T Z (factored).
template <int N, typename Factor>
struct ConstraintProjector {
  Eigen::Matrix<double, N, Eigen::Dynamic> Z;
  Eigen::LLT<Eigen::MatrixXd> s_llt;

  bool compute(const EqualityConstraints<N>& c, const Factor& factor) {
    Z.resize(c.C.rows(), c.size());
    typename Factor::Vector col;
    for (int j = 0; j < c.size(); ++j) {
      col = c.C.col(j);
      factor.solve_in_place(col);
      Z.col(j) = col;
    }
    s_llt.compute(c.C.transpose() * Z);
    return s_llt.info() == Eigen::Success;
  }
};

struct LineSearch {
  double t = 1.0;
  double full_value = 0.0;  ///< F at the full step (evaluated with derivatives into the work)
  bool accepted = false;
  bool at_floor = false;  ///< both the change of F and the predicted decrease are at round-off
};

/// Armijo backtracking from x along w.step (halving t): the full step is evaluated with its
/// derivatives (into w's trial storage; usually accepted, so one evaluation per iteration), the
/// backtracks values only. A non-finite F is a failed trial. The accepted point is w.trial.
template <typename F, typename Work, typename V>
LineSearch armijo_search(const F& f, Work& w, const V& x, double value, double slope,
                         const NewtonOptions& options, int& evaluations) {
  LineSearch ls;
  const double ulp = 8.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(value));
  for (int k = 0; k <= options.max_backtracks; ++k, ls.t *= 0.5) {
    w.trial = x + ls.t * w.step;
    const double ft =
        k == 0 ? w.evaluate(f, w.trial, w.trial_gradient, w.trial_hessian, w.trial_gauss_newton)
               : f.evaluate(w.trial, nullptr, nullptr);
    ++evaluations;
    if (k == 0) ls.full_value = ft;
    if (std::isfinite(ft) && ft <= value + options.armijo * ls.t * slope) {
      ls.accepted = true;
      return ls;
    }
    if (std::isfinite(ft) && std::abs(ft - value) <= ulp && -slope * ls.t <= ulp) {
      ls.at_floor = true;
      return ls;
    }
  }
  return ls;
}

struct NoConstraints {};

/// The loop of newton_minimize. kConstrained = false compiles none of the constraint handling
/// (its projector factors a dynamic-size S and multiplies dynamic-size blocks: about a sixth of
/// what an unconstrained call costs to compile), with the same arithmetic otherwise.
template <bool kConstrained, FactorModel Factor, typename F>
NewtonMinimum<Factor> newton_loop(
    const F& f, const typename Factor::Vector& x0, const NewtonOptions& options,
    const EqualityConstraints<Factor::Vector::RowsAtCompileTime>* constraints) {
  using V = typename Factor::Vector;
  using H = typename Factor::Hessian;
  constexpr bool kGaussNewton = HasGaussNewton<F, V, H>;
  const bool use_gn = kGaussNewton && options.fallback == HessianFallback::kGaussNewton;
  const int m = kConstrained && constraints ? constraints->size() : 0;
  NewtonMinimum<Factor> r;
  NewtonWork<Factor, kGaussNewton> w;
  std::conditional_t<kConstrained, ConstraintProjector<V::RowsAtCompileTime, Factor>, NoConstraints>
      proj;
  r.x = x0;
  r.gradient.resize(x0.size());
  w.trial_gradient.resize(x0.size());
  size_hessian(r.hessian, x0.size());
  size_hessian(w.trial_hessian, x0.size());
  if constexpr (kGaussNewton) {
    size_hessian(w.gauss_newton, x0.size());
    size_hessian(w.trial_gauss_newton, x0.size());
  }
  r.multipliers.setZero(m);
  auto evaluate_here = [&] {
    r.value = w.evaluate(f, r.x, r.gradient, r.hessian, w.gauss_newton);
    ++r.evaluations;
    return std::isfinite(r.value) && r.gradient.allFinite() && finite(r.hessian);
  };
  auto factor_here = [&] {
    r.factor_ok = factor_with_fallback(r.factor, r.hessian, use_gn ? &w.gauss_newton : nullptr,
                                       w.damped, r.exact_factor, options.damping);
    if constexpr (kConstrained)
      if (r.factor_ok && m > 0) r.factor_ok = proj.compute(*constraints, r.factor);
    return r.factor_ok;
  };
  if (!evaluate_here()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  if constexpr (kConstrained) {
    if (m > 0) {  // move onto the constraints: x += Z S^-1 (e - C^T x)
      if (!factor_here()) {
        r.status = MinimizeStatus::kNotPositiveDefinite;
        return r;
      }
      r.x += proj.Z * proj.s_llt.solve(constraints->e - constraints->C.transpose() * r.x);
      if (!evaluate_here()) {
        r.status = MinimizeStatus::kNonFinite;
        return r;
      }
    }
  }
  bool factor_current = false;  // r.factor belongs to r.x
  r.status = MinimizeStatus::kMaxIterations;
  for (;;) {
    factor_current = true;
    if (!factor_here() && (m > 0 || !options.damping)) {
      r.status = MinimizeStatus::kNotPositiveDefinite;
      break;
    }
    // The Newton step (steepest descent if nothing factored), projected onto C^T step = 0.
    w.step = r.gradient;
    if (r.factor_ok) r.factor.solve_in_place(w.step);
    if constexpr (kConstrained) {
      if (m > 0) {
        r.multipliers = -proj.s_llt.solve(constraints->C.transpose() * w.step);
        w.step += proj.Z * r.multipliers;
        w.trial = r.gradient + constraints->C * r.multipliers;  // the reduced gradient
      }
    }
    w.step = -w.step;
    const double grad_max =
        m > 0 ? w.trial.cwiseAbs().maxCoeff() : r.gradient.cwiseAbs().maxCoeff();
    const double size = w.step.cwiseAbs().maxCoeff();
    const double x_scale = options.relative_step_tolerance ? 1.0 + r.x.cwiseAbs().maxCoeff() : 1.0;
    double slope = r.gradient.dot(w.step);
    const bool small_decrement =
        options.decrement_tolerance > 0.0 && -slope < options.decrement_tolerance;
    if (grad_max <= options.gradient_tolerance || small_decrement ||
        size <= options.step_tolerance * x_scale) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
    if (r.iterations >= options.max_iterations) break;
    if (!(slope < 0.0)) {
      if (m > 0) {  // no feasible descent left at machine precision
        r.status = size <= 1e3 * options.step_tolerance * x_scale
                       ? MinimizeStatus::kConverged
                       : MinimizeStatus::kLineSearchFailed;
        break;
      }
      w.step = -r.gradient;
      slope = -r.gradient.squaredNorm();
    }
    const auto ls = armijo_search(f, w, r.x, r.value, slope, options, r.evaluations);
    const double t = ls.t;
    const bool accepted = ls.accepted, at_floor = ls.at_floor;
    if (!accepted) {  // keep x (and its factor): at the round-off floor, or a failure
      r.status = at_floor || size <= 1e3 * options.step_tolerance * x_scale
                     ? MinimizeStatus::kConverged
                     : MinimizeStatus::kLineSearchFailed;
      break;
    }
    std::swap(r.x, w.trial);
    factor_current = false;
    ++r.iterations;
    if (t == 1.0) {  // the derivatives at the full step are already there
      r.value = ls.full_value;
      std::swap(r.gradient, w.trial_gradient);
      std::swap(r.hessian, w.trial_hessian);
      if constexpr (kGaussNewton) std::swap(w.gauss_newton, w.trial_gauss_newton);
      if (!r.gradient.allFinite() || !finite(r.hessian)) {
        r.status = MinimizeStatus::kNonFinite;
        return r;
      }
    } else if (!evaluate_here()) {
      r.status = MinimizeStatus::kNonFinite;
      return r;
    }
    if (t * size <= options.step_tolerance * x_scale ||
        (r.exact_factor && t == 1.0 && size <= options.final_step)) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
  }
  if (!factor_current) factor_here();
  if (!r.factor_ok) r.status = MinimizeStatus::kNotPositiveDefinite;
  return r;
}

}  // namespace detail

/// Minimises `f` from x0 by damped Newton with the factor model `Factor`; see the file comment.
template <FactorModel Factor, typename F>
NewtonMinimum<Factor> newton_minimize(const F& f, const typename Factor::Vector& x0,
                                      const NewtonOptions& options = {}) {
  return detail::newton_loop<false, Factor>(f, x0, options, nullptr);
}

/// The same on the equality constraints C^T x = e (`constraints` may be null: none); C must
/// have as many rows as x0.
template <FactorModel Factor, typename F>
NewtonMinimum<Factor> newton_minimize(
    const F& f, const typename Factor::Vector& x0, const NewtonOptions& options,
    const EqualityConstraints<Factor::Vector::RowsAtCompileTime>* constraints) {
  return detail::newton_loop<true, Factor>(f, x0, options, constraints);
}

}  // namespace implicit
