#pragma once
// The two numerical solvers of path integral control on the banded path function: damped Newton
// with linear equality constraints (a path held at a wall's edge) and the random map's scalar
// equation along one ray. Both stay O(n) per step with the block-tridiagonal factor.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/core/banded.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control::detail {

/// Cholesky of h, adding Levenberg damping until it is positive definite. The factor then
/// defines a Gaussian proposal that is not the Laplace approximation, but the weights stay exact.
template <int B>
bool factor_damped(const BlockTridiagonal<B>& h, BlockTridiagonalCholesky<B>& factor) {
  if (factor.compute(h)) return true;
  double lambda = 1e-8;
  for (const auto& d : h.diagonal) lambda = std::max(lambda, 1e-8 * d.cwiseAbs().maxCoeff());
  BlockTridiagonal<B> damped;
  for (int i = 0; i < 60; ++i, lambda *= 10.0) {
    damped = h;
    damped.add_to_diagonal(lambda);
    if (factor.compute(damped)) return true;
  }
  return false;
}

/// |L^T v|^2 for a banded factor, without allocation.
template <int B>
double upper_norm2(const BlockTridiagonalCholesky<B>& f, const Eigen::VectorXd& v) {
  const int n = f.num_blocks();
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    Vec<B> r = f.diagonal_block(i).transpose() * v.template segment<B>(i * B);
    if (i + 1 < n)
      r.noalias() += f.subdiagonal_block(i).transpose() * v.template segment<B>((i + 1) * B);
    s += r.squaredNorm();
  }
  return s;
}

/// A linear equality a^T y_block = value (block is 0-based).
template <int D>
struct WallConstraint {
  int block = 0;
  Vec<D> a = Vec<D>::Zero();
  double value = 0.0;
};

/// Damped Newton for min F(y) subject to the equalities C^T y = e (C sparse, one column per
/// constraint), by the range-space method: Z = H^{-1} C and the small Schur complement
/// S = C^T Z, so each step stays O(n) with the banded factor. The start is first moved onto the
/// constraints by the smallest H-norm correction; every later step has C^T step = 0, so the line
/// search on F itself is valid. `nu` returns the multipliers (grad F + C nu = 0 at the solution).
template <typename PathF>
BandedMinimizeResult<PathF::Block> minimize_with_equalities(
    const PathF& f, const Eigen::VectorXd& x0,
    const std::vector<WallConstraint<PathF::Block>>& cons, const MinimizeOptions& options,
    Eigen::VectorXd& nu) {
  constexpr int D = PathF::Block;
  const int m = static_cast<int>(cons.size());
  nu.setZero(m);
  if (m == 0) return minimize_banded(f, x0, options);
  const int nb = f.num_blocks(), N = nb * D;
  BandedMinimizeResult<D> r;
  r.x = x0;
  r.gradient.resize(N);
  r.hessian.resize(nb);
  Eigen::MatrixXd Z(N, m), S(m, m);
  Eigen::LLT<Eigen::MatrixXd> s_llt;
  Eigen::VectorXd p(N), step(N), trial(N), ctp(m);
  auto c_dot = [&](int j, const auto& v) {
    return cons[j].a.dot(v.template segment<D>(cons[j].block * D));
  };
  auto factor_and_project = [&]() {
    if (!factor_damped(r.hessian, r.factor)) return false;
    for (int j = 0; j < m; ++j) {
      auto col = Z.col(j);
      col.setZero();
      col.template segment<D>(cons[j].block * D) = cons[j].a;
      r.factor.solve_in_place(col);
    }
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) S(i, j) = c_dot(i, Z.col(j));
    s_llt.compute(S);
    return s_llt.info() == Eigen::Success;
  };
  auto evaluate = [&]() {
    r.value = f.evaluate(r.x, &r.gradient, &r.hessian);
    ++r.evaluations;
    return std::isfinite(r.value) && r.gradient.allFinite() && r.hessian.all_finite();
  };
  if (!evaluate()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  if (!factor_and_project()) {
    r.status = MinimizeStatus::kNotPositiveDefinite;
    return r;
  }
  for (int j = 0; j < m; ++j) ctp(j) = cons[j].value - c_dot(j, r.x);
  r.x += Z * s_llt.solve(ctp);
  if (!evaluate()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  r.status = MinimizeStatus::kMaxIterations;
  for (r.iterations = 0; r.iterations < options.max_iterations; ++r.iterations) {
    if (!factor_and_project()) {
      r.status = MinimizeStatus::kNotPositiveDefinite;
      break;
    }
    p = r.gradient;
    r.factor.solve_in_place(p);
    for (int j = 0; j < m; ++j) ctp(j) = c_dot(j, p);
    nu = -s_llt.solve(ctp);
    step = -p - Z * nu;
    trial = r.gradient;  // the reduced gradient grad F + C nu
    for (int j = 0; j < m; ++j) trial.template segment<D>(cons[j].block * D) += nu(j) * cons[j].a;
    if (trial.cwiseAbs().maxCoeff() <= options.gradient_tolerance) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
    if (!(r.gradient.dot(step) < 0.0)) {  // no feasible descent left at machine precision
      r.status = step.cwiseAbs().maxCoeff() <=
                         1e3 * options.step_tolerance * (1.0 + r.x.cwiseAbs().maxCoeff())
                     ? MinimizeStatus::kConverged
                     : MinimizeStatus::kLineSearchFailed;
      break;
    }
    if (implicit::detail::newton_line_step(f, r, step, trial, options) !=
        implicit::detail::StepOutcome::kContinue)
      break;
  }
  if (r.status != MinimizeStatus::kNonFinite && !factor_damped(r.hessian, r.factor))
    r.status = MinimizeStatus::kNotPositiveDefinite;
  return r;
}

enum class RayOutcome { kOk, kWall, kFailed };

/// F along a ray, +inf where `inside(lambda)` is false (one mode's openings).
template <typename PathF, typename Inside>
struct RestrictedPath {
  const PathF& f;
  Inside inside;
  double evaluate_along(const Eigen::VectorXd& base, const Eigen::VectorXd& dir, double lambda,
                        double* slope) const {
    if (!inside(lambda)) {
      if (slope) *slope = 0.0;
      return std::numeric_limits<double>::infinity();
    }
    return f.evaluate_along(base, dir, lambda, slope);
  }
};
// Written out because clang before 17 does not deduce aggregate template arguments.
template <typename PathF, typename Inside>
RestrictedPath(const PathF&, Inside) -> RestrictedPath<PathF, Inside>;

/// The random map's scalar equation F(mu + lambda d) = target along one ray (spec §1.3): bracket
/// [0, hi] with hi doubled from sqrt(rho), then Newton safeguarded by bisection, to 1e-12
/// relative. kWall: F jumps to +inf before reaching the level (no root: the sample has zero
/// weight, which is exact, since no point of the ray beyond the jump has mass).
template <typename PathF>
RayOutcome solve_ray(const PathF& f, const Eigen::VectorXd& mu, const Eigen::VectorXd& d,
                     double target, double rho, double& lambda, double& slope) {
  auto g_of = [&](double l, double* s) { return f.evaluate_along(mu, d, l, s) - target; };
  double lo = 0.0, hi = std::sqrt(rho);
  double ghi = g_of(hi, nullptr);
  for (int doublings = 0; !(ghi > 0.0); ++doublings) {
    if (doublings > 200) return RayOutcome::kFailed;
    lo = hi;
    hi *= 2.0;
    ghi = g_of(hi, nullptr);
  }
  lambda = std::min(std::sqrt(rho), 0.5 * (lo + hi));
  if (lambda <= lo) lambda = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double g = g_of(lambda, &slope);
    if (g > 0.0)
      hi = lambda;
    else
      lo = lambda;
    double next = std::isfinite(g) && slope > 0.0 ? lambda - g / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double change = std::abs(next - lambda);
    lambda = next;
    if (change <= 1e-12 * lambda || hi - lo <= 1e-12 * hi) break;
  }
  const double g = g_of(lambda, &slope);
  // A root has |g| at rounding level; a finite g far from 0 with an infinite F just above means
  // the level lies beyond a jump to +inf (a wall along the ray).
  if (!std::isfinite(g) || std::abs(g) > 1e-6 * (1.0 + target))
    return std::isfinite(g_of(hi, nullptr)) ? RayOutcome::kFailed : RayOutcome::kWall;
  if (!(std::abs(slope) > 0.0) || !std::isfinite(slope)) return RayOutcome::kFailed;
  return RayOutcome::kOk;
}
}  // namespace implicit::control::detail
