#include "implicit/core/weights.hpp"

#include <algorithm>

namespace implicit {

double log_sum_exp(std::span<const double> a) {
  double m = -std::numeric_limits<double>::infinity();
  for (double v : a) m = std::max(m, v);
  if (!std::isfinite(m)) return m;  // empty, all -inf, or a +inf entry
  double s = 0.0;
  for (double v : a) s += std::exp(v - m);
  return m + std::log(s);
}

double log_mean_exp(std::span<const double> a) {
  if (a.empty()) return -std::numeric_limits<double>::infinity();
  return log_sum_exp(a) - std::log(static_cast<double>(a.size()));
}

WeightSummary normalize_log_weights(std::span<const double> log_weights,
                                    std::span<double> normalized) {
  require(log_weights.size() == normalized.size(),
          "normalize_log_weights: expected an output of size {}, got {}", log_weights.size(),
          normalized.size());
  require(!log_weights.empty(), "normalize_log_weights: expected at least one weight, got none");
  for (std::size_t i = 0; i < log_weights.size(); ++i)
    require(
        !std::isnan(log_weights[i]) && log_weights[i] != std::numeric_limits<double>::infinity(),
        "normalize_log_weights: log-weight {} is {} (expected a number or -inf)", i,
        log_weights[i]);
  WeightSummary s;
  const double lse = log_sum_exp(log_weights);
  const double n = static_cast<double>(log_weights.size());
  if (!std::isfinite(lse)) {
    s.all_zero = true;
    std::fill(normalized.begin(), normalized.end(), 1.0 / n);
    s.ess = n;
    return s;
  }
  for (std::size_t i = 0; i < log_weights.size(); ++i)
    normalized[i] = std::exp(log_weights[i] - lse);
  s.log_mean = lse - std::log(n);
  s.ess = effective_sample_size(normalized);
  return s;
}

double effective_sample_size(std::span<const double> normalized) {
  double s2 = 0.0;
  for (double w : normalized) s2 += w * w;
  return s2 > 0.0 ? 1.0 / s2 : 0.0;
}

double relative_standard_error(std::span<const double> log_weights) {
  const std::size_t n = log_weights.size();
  if (n < 2) return std::numeric_limits<double>::infinity();
  double m = -std::numeric_limits<double>::infinity();
  for (double v : log_weights) m = std::max(m, v);
  if (!std::isfinite(m)) return std::numeric_limits<double>::infinity();
  double s1 = 0.0, s2 = 0.0;
  for (double v : log_weights) {
    const double w = std::exp(v - m);
    s1 += w;
    s2 += w * w;
  }
  const double mean = s1 / n;
  const double var = std::max(0.0, (s2 / n - mean * mean) * n / (n - 1.0));
  return std::sqrt(var / n) / mean;
}

WeightMoments weight_moments(std::span<const double> log_weights) {
  WeightMoments r;
  const std::size_t n = log_weights.size();
  double m = -std::numeric_limits<double>::infinity();
  for (double v : log_weights) m = std::max(m, v);
  if (!std::isfinite(m)) {
    if (m > 0.0) r.log_mean = m;  // a +inf entry, as log_mean_exp
    return r;
  }
  double s1 = 0.0, s2 = 0.0;
  for (double v : log_weights) {
    const double w = std::exp(v - m);
    s1 += w;
    s2 += w * w;
  }
  const double nd = static_cast<double>(n);
  r.log_mean = m + std::log(s1) - std::log(nd);
  r.ess = s1 * s1 / s2;
  if (n >= 2) {
    const double mean = s1 / nd;
    const double var = std::max(0.0, (s2 / nd - mean * mean) * nd / (nd - 1.0));
    r.relative_se = std::sqrt(var / nd) / mean;
  }
  return r;
}

double circular_mean(std::span<const double> angles, std::span<const double> w) {
  require(angles.size() == w.size(), "circular_mean: expected {} weights, got {}", angles.size(),
          w.size());
  double s = 0.0, c = 0.0;
  for (std::size_t i = 0; i < angles.size(); ++i) {
    s += w[i] * std::sin(angles[i]);
    c += w[i] * std::cos(angles[i]);
  }
  return std::atan2(s, c);
}

}  // namespace implicit
