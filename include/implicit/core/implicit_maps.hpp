#pragma once
// The two maps of implicit sampling, generic over the Gaussian factor (gaussian_factor.hpp), and
// the one root finder of the random map.
//
//   linear map:  X = mu + L^{-T} xi
//   random map:  X = mu + lambda d, d = L^{-T} xi / |xi|, lambda > 0 solving
//                F(mu + lambda d) - phi = |xi|^2 / 2   (solve_random_map_ray)
//
// Both weigh with implicit_log_weight (log_weight.hpp); the random map with the corrected
// Jacobian (random_map.hpp explains the correction). The objective needs
// `double evaluate(const Vector& x, Vector* grad, Hessian* hess) const` in the factor's types
// (called with a null Hessian). Root finding: bracket [0, hi] (hi doubled from sqrt(rho) until
// g > 0), then Newton steps safeguarded by bisection, to a relative tolerance of 1e-12.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/log_weight.hpp"

namespace implicit {

enum class RayStatus {
  kOk,
  kBracketFailed,   ///< g never became positive (F bounded along the ray)
  kNotConverged,    ///< root not found to tolerance within the iteration limit
  kZeroDerivative,  ///< grad F . d = 0 at the root (the map is singular there)
  kJump,            ///< F jumps over the level to +inf (a wall): no root, weight exactly 0
};

inline std::string_view to_string(RayStatus s) {
  switch (s) {
    case RayStatus::kOk:
      return "ok";
    case RayStatus::kBracketFailed:
      return "bracket_failed";
    case RayStatus::kNotConverged:
      return "not_converged";
    case RayStatus::kZeroDerivative:
      return "zero_derivative";
    case RayStatus::kJump:
      return "jump";
  }
  return "unknown";
}

/// The root finder's tolerances and limits.
struct RandomMapOptions {
  double relative_tolerance = 1e-12;
  int max_iterations = 200;
  int max_doublings = 200;
};

/// X = mu + L^{-T} xi written to `x`; returns log w (implicit_log_weight).
template <GaussianFactor Factor, typename F, typename XiDerived>
double linear_map(const F& f, const typename Factor::Vector& mu, const Factor& factor,
                  const Eigen::MatrixBase<XiDerived>& xi, typename Factor::Vector& x) {
  // Solved in a local, then added: in place in x, the solve's scalar stores stall the vector
  // loads of `x += mu` (store forwarding; 1.2x the cost at m = 5 in bench_core).
  typename Factor::Vector offset = xi;
  factor.upper_solve_in_place(offset);
  x = mu + offset;
  return implicit_log_weight(static_cast<int>(mu.size()), xi.squaredNorm(),
                             f.evaluate(x, nullptr, nullptr), factor.log_det_L());
}

/// The one root finder of the random map: lambda > 0 with g(lambda) = 0, where
/// g(lambda) = F(mu + lambda d) - level and g(0) = -rho/2 < 0. `g(lambda, &slope)` returns g
/// (+inf or NaN outside the support) and, if slope is not null, g'(lambda). Bracket [0, hi] with
/// hi doubled from sqrt(rho) until g(hi) > 0, then Newton steps safeguarded by bisection. On
/// return `lambda` is the root and `slope` = g'(lambda). kJump: F jumps over the level (to +inf)
/// instead of crossing it; no point of the ray maps there, so the sample's weight is exactly 0.
/// That includes a jump at lambda = 0+ (mu on the edge of the support, the ray leaving it): if
/// every g seen is +inf and the bracket [0, hi] has shrunk to hi <= relative_tolerance *
/// sqrt(rho), the ray is taken to jump at 0 (a relative tolerance cannot be met on a bracket
/// whose lower end is 0; a root below that hi would need F to climb rho / 2 within a tolerance's
/// fraction of the quadratic model's root sqrt(rho)).
template <typename G>
RayStatus solve_random_map_ray(const G& g_in, double rho, double level, double& lambda,
                               double& slope, const RandomMapOptions& options = {}) {
  // NaN means outside the support, like +inf (the comparisons below would take it for "below").
  auto g_of = [&g_in](double l, double* s) {
    const double g = g_in(l, s);
    return std::isnan(g) ? std::numeric_limits<double>::infinity() : g;
  };
  double lo = 0.0, hi = std::sqrt(rho);
  const double jump_at_zero = options.relative_tolerance * hi;
  double ghi = g_of(hi, nullptr);
  bool only_infinite = std::isinf(ghi);  // no finite g yet (a doubling moves lo off 0 anyway)
  int doublings = 0;
  while (!(ghi > 0.0)) {  // an infinite or NaN F also ends the bracket
    if (++doublings > options.max_doublings) return RayStatus::kBracketFailed;
    lo = hi;
    hi *= 2.0;
    ghi = g_of(hi, nullptr);
  }
  // Safeguarded Newton from the quadratic-model root (exact for Gaussian F: lambda = sqrt(rho)).
  lambda = std::min(std::sqrt(rho), 0.5 * (lo + hi));
  if (lambda <= lo) lambda = 0.5 * (lo + hi);
  bool converged = false;
  for (int it = 0; it < options.max_iterations; ++it) {
    const double g = g_of(lambda, &slope);
    if (g > 0.0)
      hi = lambda;
    else
      lo = lambda;
    only_infinite = only_infinite && std::isinf(g);
    if (only_infinite && lo == 0.0 && hi <= jump_at_zero) return RayStatus::kJump;
    double next = std::isfinite(g) && slope > 0.0 ? lambda - g / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double change = std::abs(next - lambda);
    lambda = next;
    if (change <= options.relative_tolerance * lambda ||
        hi - lo <= options.relative_tolerance * hi) {
      converged = true;
      break;
    }
  }
  const double g = g_of(lambda, &slope);
  // A root has |g| at rounding level; a finite g far from 0 with an infinite F just above means
  // the level lies beyond a jump to +inf.
  if (!std::isfinite(g) || std::abs(g) > 1e-6 * (1.0 + std::abs(level)))
    return converged && !std::isfinite(g_of(hi, nullptr)) ? RayStatus::kJump
                                                          : RayStatus::kNotConverged;
  if (!converged) return RayStatus::kNotConverged;
  if (!(std::abs(slope) > 0.0) || !std::isfinite(slope)) return RayStatus::kZeroDerivative;
  return RayStatus::kOk;
}

/// The random map for centre mu, phi = F(mu) and the factor of H: solves for `xi`, writes X to
/// `x` and log w to `log_weight` (implicit_log_weight with the corrected Jacobian). On failure
/// the sample gets log w = -inf and the status says why (never throws). The objective needs
/// `double evaluate(const Vector& x, Vector* grad, Hessian* hess) const` (hess null).
template <GaussianFactor Factor, typename F, typename XiDerived>
RayStatus random_map(const F& f, const typename Factor::Vector& mu, double phi,
                     const Factor& factor, const Eigen::MatrixBase<XiDerived>& xi,
                     typename Factor::Vector& x, double& log_weight,
                     const RandomMapOptions& options = {}) {
  using V = typename Factor::Vector;
  const int m = static_cast<int>(mu.size());
  const double rho = xi.squaredNorm();
  log_weight = -std::numeric_limits<double>::infinity();
  if (!(rho > 1e-300)) {  // xi = 0 has probability zero; map it to the mode, weight 0
    x = mu;
    return RayStatus::kZeroDerivative;
  }
  V d = xi / std::sqrt(rho);
  factor.upper_solve_in_place(d);
  const double level = phi + 0.5 * rho;
  V grad(m);
  auto g_of = [&](double lambda, double* slope) {
    x = mu + lambda * d;
    const double fx = f.evaluate(x, slope ? &grad : nullptr, nullptr);
    if (slope) *slope = grad.dot(d);
    return std::isnan(fx) ? std::numeric_limits<double>::infinity() : fx - level;
  };
  double lambda = 0.0, slope = 0.0;
  const RayStatus status = solve_random_map_ray(g_of, rho, level, lambda, slope, options);
  if (status != RayStatus::kOk) return status;
  x = mu + lambda * d;
  log_weight = implicit_log_weight(m, rho, level, factor.log_det_L(),
                                   random_map_log_jacobian(m, rho, lambda, slope));
  return RayStatus::kOk;
}

}  // namespace implicit
