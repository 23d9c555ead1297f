#pragma once
// The one implicit-sampling weight (spec §1.2, §1.3), for both maps and every caller.
//
// A sample X = x(xi) with xi ~ N(0, I_m) has proposal density q(X) = N(xi; 0, I) / |det dX/dxi|,
// so its weight exp(-F(X)) / q(X) is, in the log domain,
//
//   log w = (m/2) log 2pi + |xi|^2/2 - F(X) + log|det dX/dxi|,   log|det dX/dxi| = -log det L + r
//
// with r = 0 for the linear map X = mu + L^{-T} xi, and for the random map X = mu + lambda d,
// d = L^{-T} xi/|xi|, F(X) = phi + |xi|^2/2 (the corrected Jacobian, see random_map.hpp):
//
//   r = (1 - m/2) log rho + (m - 1) log lambda - log|grad F(X) . d|,   rho = |xi|^2.
//
// F must include every constant that differs between particles (1/2 log det 2 pi Sigma of each
// Gaussian factor): then E[w] = Z and weights of different targets are comparable. A sample
// with F(X) = +inf or NaN (outside the support) gets log w = -inf.

#include <cmath>
#include <limits>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

/// log w of an implicit sample: m = dimension, rho = |xi|^2, f_x = F(X), log_det_L of the factor
/// used, log_ray_jacobian = r above (0 for the linear map).
inline double implicit_log_weight(int m, double rho, double f_x, double log_det_L,
                                  double log_ray_jacobian = 0.0) {
  if (!(f_x < std::numeric_limits<double>::infinity()))  // +inf or NaN: outside the support
    return -std::numeric_limits<double>::infinity();
  return gaussian_log_normaliser(m, 0.0) + 0.5 * rho - f_x - log_det_L + log_ray_jacobian;
}

/// The random map's r = (1 - m/2) log rho + (m - 1) log lambda - log|slope|, slope = grad F . d.
inline double random_map_log_jacobian(int m, double rho, double lambda, double slope) {
  const double md = static_cast<double>(m);
  return (1.0 - 0.5 * md) * std::log(rho) + (md - 1.0) * std::log(lambda) -
         std::log(std::abs(slope));
}

}  // namespace implicit
