#pragma once
// The random map of implicit sampling (scalar equation along a random direction), for a dense
// target and its Laplace approximation.
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
// random_map_sample() is the kernel's random_map (implicit_maps.hpp: the one root finder,
// solve_random_map_ray, and the one weight, implicit_log_weight) with the factor L of the Laplace
// approximation. Everything is in the log domain: rho^{1 - m/2} underflows for m = 100.

#include <cmath>

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/laplace.hpp"
#include "implicit/core/target.hpp"

namespace implicit {

/// The outcome of a random-map sample: the root finder's status (kJump: F jumps over the level
/// to +inf along the ray, so no point maps there and the weight is exactly 0).
using RandomMapStatus = RayStatus;

/// Solves the scalar equation for `xi`, writes X to `x` and log w to `log_weight`.
/// On failure the sample gets log w = -inf and the status says why (never throws).
template <Target T, typename XiDerived>
RandomMapStatus random_map_sample(const T& f, const Laplace<T::Dim>& lp,
                                  const Eigen::MatrixBase<XiDerived>& xi, typename T::Vector& x,
                                  double& log_weight, const RandomMapOptions& options = {}) {
  return random_map(f, lp.mu, lp.phi, lp.factor(), xi, x, log_weight, options);
}

/// The paper's eq. (3) Jacobian (too small by 2 sqrt(rho)); kept only to document the bias.
/// Returns the log-weight the paper's formula would assign to the same sample.
inline double paper_random_map_log_weight(double corrected_log_weight, double rho) {
  return corrected_log_weight - std::log(2.0 * std::sqrt(rho));
}

}  // namespace implicit
