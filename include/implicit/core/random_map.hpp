#pragma once
// The random map of implicit sampling (scalar equation along a random direction).
//
//   rho = |xi|^2, eta = xi / sqrt(rho), d = L^{-T} eta, X = mu + lambda d, where lambda > 0 solves
//   g(lambda) = F(mu + lambda d) - phi - rho/2 = 0.
//   J = |det dX/dxi| = rho^{1 - m/2} lambda^{m-1} / (det L |grad F(X) . d|)
//   log w = (m/2) log 2pi - phi + log J
//
// This Jacobian is the corrected one: the paper's eq. (3)/(4) is too small by a factor 2 sqrt(rho)
// that varies between samples and biases Z-hat (see tests/core/oracles_test.cpp, T2 and T4).
// The map is one-to-one only if F - phi increases monotonically along every ray from mu
// ("star-shaped" targets, e.g. convex F); banana-shaped targets need the linear map.
// Root finding: bracket [0, hi] (hi doubled from sqrt(rho) until g > 0), then Newton steps
// safeguarded by bisection, to a relative tolerance of 1e-12. Everything is in the log domain:
// rho^{1 - m/2} underflows for m = 100.

#include <cmath>
#include <limits>
#include <string_view>

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/laplace.hpp"
#include "implicit/core/target.hpp"

namespace implicit {

enum class RandomMapStatus {
  kOk,
  kBracketFailed,   ///< g never became positive (F bounded along the ray)
  kNotConverged,    ///< root not found to tolerance within the iteration limit
  kZeroDerivative,  ///< grad F . d = 0 at the root (the map is singular there)
};

inline std::string_view to_string(RandomMapStatus s) {
  switch (s) {
    case RandomMapStatus::kOk:
      return "ok";
    case RandomMapStatus::kBracketFailed:
      return "bracket_failed";
    case RandomMapStatus::kNotConverged:
      return "not_converged";
    case RandomMapStatus::kZeroDerivative:
      return "zero_derivative";
  }
  return "unknown";
}

/// Solves the scalar equation for `xi`, writes X to `x` and log w to `log_weight`.
/// On failure the sample gets log w = -inf and the status says why (never throws).
template <Target T, typename XiDerived>
RandomMapStatus random_map_sample(const T& f, const Laplace<T::Dim>& lp,
                                  const Eigen::MatrixBase<XiDerived>& xi, typename T::Vector& x,
                                  double& log_weight, const RandomMapOptions& options = {}) {
  using V = typename T::Vector;
  const int m = lp.dim();
  const double md = static_cast<double>(m);
  const double rho = xi.squaredNorm();
  log_weight = -std::numeric_limits<double>::infinity();
  if (!(rho > 1e-300)) {  // xi = 0 has probability zero; map it to the mode, weight 0
    x = lp.mu;
    return RandomMapStatus::kZeroDerivative;
  }
  const V eta = xi / std::sqrt(rho);
  const V d = lp.L.transpose().template triangularView<Eigen::Upper>().solve(eta);
  const double target = lp.phi + 0.5 * rho;
  V grad(m);
  auto g_of = [&](double lambda, double* slope) {
    x = lp.mu + lambda * d;
    const double fx = f.evaluate(x, slope ? &grad : nullptr, nullptr);
    if (slope) *slope = grad.dot(d);
    return std::isnan(fx) ? std::numeric_limits<double>::infinity() : fx - target;
  };
  // Bracket: g(0) = -rho/2 < 0; grow hi until g(hi) > 0 (an infinite F also counts).
  double lo = 0.0, hi = std::sqrt(rho);
  double ghi = g_of(hi, nullptr);
  int doublings = 0;
  while (!(ghi > 0.0)) {
    if (++doublings > options.max_doublings) return RandomMapStatus::kBracketFailed;
    lo = hi;
    hi *= 2.0;
    ghi = g_of(hi, nullptr);
  }
  // Safeguarded Newton from the quadratic-model root (exact for Gaussian F: lambda = sqrt(rho)).
  double lambda = std::min(std::sqrt(rho), 0.5 * (lo + hi));
  if (lambda <= lo) lambda = 0.5 * (lo + hi);
  double slope = 0.0;
  bool converged = false;
  for (int it = 0; it < options.max_iterations; ++it) {
    const double g = g_of(lambda, &slope);
    if (g > 0.0)
      hi = lambda;
    else
      lo = lambda;
    double next;
    if (std::isfinite(g) && slope > 0.0) {
      next = lambda - g / slope;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    } else {
      next = 0.5 * (lo + hi);
    }
    const double change = std::abs(next - lambda);
    lambda = next;
    if (change <= options.relative_tolerance * lambda ||
        hi - lo <= options.relative_tolerance * hi) {
      converged = true;
      break;
    }
  }
  const double g = g_of(lambda, &slope);
  if (!converged || !std::isfinite(g)) return RandomMapStatus::kNotConverged;
  if (!(std::abs(slope) > 0.0) || !std::isfinite(slope)) return RandomMapStatus::kZeroDerivative;
  log_weight = 0.5 * md * kLog2Pi - lp.phi - lp.log_det_L + (1.0 - 0.5 * md) * std::log(rho) +
               (md - 1.0) * std::log(lambda) - std::log(std::abs(slope));
  return RandomMapStatus::kOk;
}

/// The paper's eq. (3) Jacobian (too small by 2 sqrt(rho)); kept only to document the bias.
/// Returns the log-weight the paper's formula would assign to the same sample.
inline double paper_random_map_log_weight(double corrected_log_weight, double rho) {
  return corrected_log_weight - std::log(2.0 * std::sqrt(rho));
}

}  // namespace implicit
