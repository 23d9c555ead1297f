#include "implicit/control/normal_tail.hpp"

#include <cmath>
#include <limits>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

double log_normal_cdf(double z) {
  if (std::isnan(z)) return z;
  if (z == std::numeric_limits<double>::infinity()) return 0.0;
  if (z == -std::numeric_limits<double>::infinity())
    return -std::numeric_limits<double>::infinity();
  if (z > 5.0) return std::log1p(-0.5 * std::erfc(z / std::sqrt(2.0)));
  if (z > -30.0) return std::log(0.5 * std::erfc(-z / std::sqrt(2.0)));
  // Mills-ratio series: Phi(z) = phi(z)/|z| (1 - 1/z^2 + 3/z^4 - 15/z^6 + 105/z^8 - ...);
  // the first omitted term is 945/z^10 < 2e-12 for z < -30.
  const double r = 1.0 / (z * z);
  const double series = 1.0 - r * (1.0 - 3.0 * r * (1.0 - 5.0 * r * (1.0 - 7.0 * r)));
  return log_normal_pdf(z) - std::log(-z) + std::log(series);
}

double log_normal_pdf(double z) { return -0.5 * z * z - gaussian_log_normaliser(1, 0.0); }

double log_normal_interval(double a, double b) {
  if (!(a < b)) return -std::numeric_limits<double>::infinity();
  if (a > 0.0) {
    // Upper tail: Q(a) - Q(b) with Q(z) = Phi(-z).
    const double la = log_normal_cdf(-a);
    const double lb = log_normal_cdf(-b);
    return la + std::log1p(-std::exp(lb - la));
  }
  if (b < 0.0) {
    const double lb = log_normal_cdf(b);
    const double la = log_normal_cdf(a);
    return lb + std::log1p(-std::exp(la - lb));
  }
  // The interval contains 0: the difference is at least Phi(b) - 1/2 or 1/2 - Phi(a), no
  // cancellation beyond the absolute rounding of the cdfs.
  return std::log(0.5 * (std::erfc(-b / std::sqrt(2.0)) - std::erfc(-a / std::sqrt(2.0))));
}

}  // namespace implicit::control
