#pragma once
// Helpers for the randomised tests of the core: estimators with their standard errors
// (math spec §1.5) and a gtest assertion "estimate within k standard errors of the truth".
//
// Tolerance rule (spec §1.5): with a fixed seed and M >= 10^4 samples, the estimators are close to
// normal, so |estimate - exact| <= 4.5 SE fails for a correct code with probability ~7e-6 per
// check. The smallest bias such a check detects reliably is about 4.5 SE (printed on failure).

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/implicit_sampler.hpp"

namespace implicit::testing {

/// An estimate and its standard error.
struct Estimate {
  double value = 0.0;
  double se = 0.0;
  double z(double exact) const { return (value - exact) / se; }
};

/// Mean, sample standard deviation and standard error of independent runs of an experiment.
struct RunSummary {
  double mean = 0.0, sd = 0.0, se = 0.0;
};
inline RunSummary summarise_runs(std::span<const double> v) {
  const double n = static_cast<double>(v.size());
  RunSummary s;
  for (double x : v) s.mean += x / n;
  double q = 0.0;
  for (double x : v) q += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(q / (n - 1.0));
  s.se = s.sd / std::sqrt(n);
  return s;
}

/// Z-hat = mean of the raw weights exp(l_j), SE = sd(w)/sqrt(M) (spec §1.5). Weights are scaled
/// by exp(max l) only implicitly: the oracles keep log-weights of order 1, so exp is safe.
inline Estimate normalising_constant(std::span<const double> log_weights) {
  const double m = static_cast<double>(log_weights.size());
  double s1 = 0.0, s2 = 0.0;
  for (double l : log_weights) {
    const double w = std::exp(l);
    s1 += w;
    s2 += w * w;
  }
  const double mean = s1 / m;
  const double var = std::max(0.0, (s2 / m - mean * mean) * m / (m - 1.0));
  return {mean, std::sqrt(var / m)};
}

/// Self-normalised E-hat[h] = sum w_bar_j h_j with SE = sqrt(sum w_bar_j^2 (h_j - E-hat)^2)
/// (the delta-method standard error of a ratio estimator, spec §1.5).
inline Estimate weighted_moment(std::span<const double> normalized, std::span<const double> h) {
  double e = 0.0;
  for (std::size_t j = 0; j < h.size(); ++j) e += normalized[j] * h[j];
  double v = 0.0;
  for (std::size_t j = 0; j < h.size(); ++j) {
    const double d = h[j] - e;
    v += normalized[j] * normalized[j] * d * d;
  }
  return {e, std::sqrt(v)};
}

/// E-hat[h(X)] over a sample set, for a function of one sample (a column).
template <int N, typename H>
Estimate moment(const SampleSet<N>& s, H&& h) {
  std::vector<double> values(s.size());
  for (std::size_t j = 0; j < s.size(); ++j) values[j] = h(s.x.col(static_cast<Eigen::Index>(j)));
  return weighted_moment(s.weights, values);
}

/// gtest predicate: |estimate - exact| <= k SE, with the z-score in the failure message.
inline ::testing::AssertionResult WithinStandardErrors(const Estimate& e, double exact,
                                                       double k = 4.5) {
  if (std::getenv("IMPLICIT_TEST_VERBOSE"))  // to inspect z-scores of passing checks
    fmt::print("  estimate {:.8g} exact {:.8g} SE {:.3g} z {:+.2f}\n", e.value, exact, e.se,
               (e.value - exact) / e.se);
  if (std::isfinite(e.value) && e.se > 0.0 && std::abs(e.value - exact) <= k * e.se)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << fmt::format(
             "estimate {:.10g} vs exact {:.10g}: SE {:.3g}, z = {:.2f} (allowed |z| <= {})",
             e.value, exact, e.se, (e.value - exact) / e.se, k);
}

}  // namespace implicit::testing
