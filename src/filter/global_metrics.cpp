// Metrics of global localization and kidnapping runs (spec §3.11).
#include <algorithm>
#include <cmath>

#include "implicit/filter/global_run.hpp"

namespace implicit::filter {

GlobalMetrics global_metrics(const LocalizationRun& run, const LocalizationProblem& problem,
                             double from, const GlobalCriteria& criteria) {
  require(criteria.threshold > 0 && criteria.settle >= 0,
          "global metrics: expected a positive threshold and a non-negative settle time, got {} "
          "and {}",
          criteria.threshold, criteria.settle);
  const auto& times = problem.schedule.steps;
  const std::size_t n = run.steps.size();
  require(run.first_step + n <= times.size() && problem.truth.position.size() == times.size(),
          "global metrics: the run ({} steps from step {}) does not match the problem ({} steps, "
          "{} truth positions)",
          n, run.first_step, times.size(), problem.truth.position.size());
  GlobalMetrics m;
  double sum = 0.0;
  int count = 0;
  // The candidate start of convergence: the first step of the current stretch below threshold.
  double below_since = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < n; ++k) {
    const StepSummary& s = run.steps[k];
    m.particles_mean += static_cast<double>(s.particles);
    m.particles_peak = std::max(m.particles_peak, static_cast<double>(s.particles));
    m.injected += s.injected;
    const std::size_t step = run.first_step + k;
    const Vec<2>& truth = problem.truth.position[step];
    const double t = times[step].time;
    if (t < from || !truth.allFinite()) continue;
    const double e = (s.mean.head<2>() - truth).norm();
    if (t >= from + criteria.settle) {
      sum += e * e;
      ++count;
    }
    if (!std::isnan(m.time_to_converge)) continue;
    if (e >= criteria.threshold) {
      below_since = std::numeric_limits<double>::quiet_NaN();
    } else if (std::isnan(below_since)) {
      below_since = t;
    } else if (t - below_since >= 5.0) {
      m.time_to_converge = below_since - from;
    }
  }
  if (n > 0) m.particles_mean /= static_cast<double>(n);
  if (count > 0) {
    m.rmse_after_settle = std::sqrt(sum / count);
    m.success = m.rmse_after_settle < criteria.threshold;
  }
  return m;
}

}  // namespace implicit::filter
