#pragma once
// The normal density's normalising constant, written once. Every layer needs it: the implicit
// weight (spec §1.2), the motion prior and the sensor terms of the pose objectives, the mixtures
// of global localization, the path measures of control and the data-assimilation filters.
//
// A Gaussian N(mu, Sigma) of dimension m with Sigma = L L^T has the density
//   exp(-r^2 / 2) / Z,  r^2 = (x - mu)^T Sigma^-1 (x - mu),  log Z = m/2 log(2 pi) + log det L,
// and log det L = 1/2 log det Sigma is what a Cholesky factor gives for free. Callers holding the
// factor of the precision H = Sigma^-1 instead pass -log det L_H.
//
//   gaussian_log_density(3, sigma1.log_det_L(), eta.squaredNorm())   // log N(x; f, Sigma1)
//   objective.add_constant(gaussian_log_normaliser(2, 0.5 * log_det_r))  // F = -log p + ...
//
// Some callers pass log_det_sqrt = 0 and add their determinant terms after: floating-point sums
// depend on their order, and a weight that moves by one ulp changes which particles resampling
// keeps, so a formula keeps the order it had and its results stay bit-identical.

#include <cmath>

#include "implicit/core/types.hpp"

namespace implicit {

/// log Z = 1/2 log det(2 pi Sigma) for an m-dimensional Gaussian whose covariance has
/// log det L = `log_det_sqrt` (Sigma = L L^T). The constant an objective F = -log p carries.
constexpr double gaussian_log_normaliser(int dim, double log_det_sqrt) {
  return 0.5 * static_cast<double>(dim) * kLog2Pi + log_det_sqrt;
}

/// log N(x; mu, Sigma) from the squared Mahalanobis distance r^2 = (x - mu)^T Sigma^-1 (x - mu).
constexpr double gaussian_log_density(int dim, double log_det_sqrt, double squared_distance) {
  return -gaussian_log_normaliser(dim, log_det_sqrt) - 0.5 * squared_distance;
}

/// Z = sqrt(2 pi) sd of a one-dimensional Gaussian with standard deviation `sd`.
inline double gaussian_normaliser(double sd) { return std::sqrt(2.0 * kPi) * sd; }

}  // namespace implicit
