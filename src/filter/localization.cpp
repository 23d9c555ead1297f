#include "implicit/filter/localization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::filter {

LocalizationProblem make_problem(const robot::RobotLog& log, double dt) {
  robot::require_runnable(log);
  require(!log.landmarks.empty(), "localization: expected 'landmark' records (the map), got none");
  LocalizationProblem p;
  p.map = log.landmarks;
  p.initial_mean = log.initial->mean;
  p.initial_covariance = log.initial->std.cwiseAbs2().asDiagonal();
  p.schedule = robot::make_schedule(log, log.initial->time, 0.5 * dt);
  require(!p.schedule.steps.empty(), "localization: expected controls after the initial time {}",
          log.initial->time);
  p.step_dt = robot::step_lengths(log, p.schedule, dt);
  p.detections.resize(p.schedule.steps.size());
  for (std::size_t n = 0; n < p.schedule.steps.size(); ++n) {
    const int scan = p.schedule.steps[n].scan;
    if (scan < 0) continue;
    const robot::ObservationSet& set = log.scans[static_cast<std::size_t>(scan)];
    for (const robot::Observation& o : set.observations) {
      const int index = o.landmark_id >= 0 ? p.map.index_of(o.landmark_id) : -1;
      require(o.landmark_id < 0 || index >= 0,
              "localization: the scan at t = {} names landmark id {}, which the map does not have",
              set.time, o.landmark_id);
      p.detections[n].push_back({o.z, index});
      ++p.detections_total;
    }
  }
  p.truth = robot::interpolate_truth(log, p.schedule);
  // Each truth record goes to the step nearest in time (steps are sorted), if within dt / 2.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  p.position_fixes.assign(p.schedule.steps.size(), Vec<2>(nan, nan));
  for (const robot::TruthRecord& t : log.truth) {
    const auto it =
        std::lower_bound(p.schedule.steps.begin(), p.schedule.steps.end(), t.time,
                         [](const robot::FilterStep& s, double time) { return s.time < time; });
    std::size_t best = p.schedule.steps.size();
    double best_gap = 0.5 * dt;
    for (auto c : {it, it == p.schedule.steps.begin() ? it : it - 1}) {
      if (c == p.schedule.steps.end()) continue;
      const double gap = std::abs(c->time - t.time);
      if (gap <= best_gap) {
        best_gap = gap;
        best = static_cast<std::size_t>(c - p.schedule.steps.begin());
      }
    }
    if (best < p.position_fixes.size()) p.position_fixes[best] = t.position;
  }
  return p;
}

LocalizationMetrics localization_metrics(const LocalizationRun& run, const robot::TruthTrack& truth,
                                         std::size_t particles) {
  require(run.steps.size() == truth.position.size(),
          "localization metrics: expected {} truth entries, got {}", run.steps.size(),
          truth.position.size());
  LocalizationMetrics m;
  double num = 0.0, den = 0.0, hsum = 0.0;
  int n = 0, nh = 0, updates = 0;
  double ess = 0.0, newton = 0.0;
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    const StepSummary& s = run.steps[k];
    m.detections_used += s.detections_used;
    m.detections_dropped += s.detections_dropped;
    m.gated += s.gated;
    m.fallbacks += s.fallbacks;
    m.failures += s.failures;
    if (s.updated) {
      ess += s.ess / static_cast<double>(particles);
      newton += s.newton_evaluations;
      m.min_log_likelihood_increment =
          updates == 0 ? s.log_likelihood_increment
                       : std::min(m.min_log_likelihood_increment, s.log_likelihood_increment);
      ++updates;
    }
    const Vec<2>& p = truth.position[k];
    if (!p.allFinite()) continue;
    const double e2 = (s.mean.head<2>() - p).squaredNorm();
    num += e2;
    den += p.squaredNorm();
    m.max_error = std::max(m.max_error, std::sqrt(e2));
    ++n;
    if (std::isfinite(truth.heading[k])) {
      hsum += std::pow(wrap_angle(s.mean(2) - truth.heading[k]), 2);
      ++nh;
    }
  }
  if (n == 0) {
    // Nothing to compare with (a log without truth): NaN (null in JSON), not an error of 0.
    m.error_percent = m.rmse = m.max_error = std::numeric_limits<double>::quiet_NaN();
  } else {
    m.error_percent = 100.0 * std::sqrt(num) / std::sqrt(den);
    m.rmse = std::sqrt(num / n);
  }
  if (nh > 0) m.heading_rmse = std::sqrt(hsum / nh);
  if (updates > 0) {
    m.ess_fraction = ess / updates;
    m.newton_evaluations = newton / updates;
  }
  return m;
}

double error_percent(const std::vector<Pose>& estimate, const robot::TruthTrack& truth) {
  require(estimate.size() == truth.position.size(), "error_percent: expected {} estimates, got {}",
          truth.position.size(), estimate.size());
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    if (!truth.position[k].allFinite()) continue;
    num += (estimate[k].head<2>() - truth.position[k]).squaredNorm();
    den += truth.position[k].squaredNorm();
  }
  return 100.0 * std::sqrt(num / den);
}

}  // namespace implicit::filter

namespace implicit::filter {

LocalizationProblem without_steps(const LocalizationProblem& problem, double from, double to) {
  require(from <= to && !std::isnan(from) && !std::isnan(to),
          "without_steps: expected an interval from <= to, got [{}, {})", from, to);
  const std::size_t n = problem.schedule.steps.size();
  const bool has_truth = problem.truth.position.size() == n;
  const bool has_heading = problem.truth.heading.size() == n;
  const bool has_fixes = problem.position_fixes.size() == n;
  LocalizationProblem out = problem;
  out.schedule.steps.clear();
  out.step_dt.clear();
  out.detections.clear();
  out.truth = {};
  out.position_fixes.clear();
  out.detections_total = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = problem.schedule.steps[k].time;
    if (t >= from && t < to) continue;
    out.schedule.steps.push_back(problem.schedule.steps[k]);
    if (!problem.step_dt.empty()) out.step_dt.push_back(problem.step_dt[k]);
    out.detections.push_back(problem.detections[k]);
    out.detections_total += static_cast<int>(problem.detections[k].size());
    if (has_truth) out.truth.position.push_back(problem.truth.position[k]);
    if (has_heading) out.truth.heading.push_back(problem.truth.heading[k]);
    if (has_fixes) out.position_fixes.push_back(problem.position_fixes[k]);
  }
  require(!out.schedule.steps.empty(),
          "without_steps: removing [{}, {}) s leaves no step of the log", from, to);
  return out;
}

}  // namespace implicit::filter
