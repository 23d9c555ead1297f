#pragma once
// Summaries over the runs of an experiment: mean, sample standard deviation, median (a field of
// every record: column() in run_record.hpp).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "experiments/run_record.hpp"

namespace implicit::experiments {

inline double mean_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

inline double sd_of(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean_of(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

/// The median (0 for no values).
inline double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The median of the finite values, NaN when there are none (e.g. runs that never converged).
inline double median_of_finite(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  return v.empty() ? std::nan("") : median_of(std::move(v));
}

}  // namespace implicit::experiments
