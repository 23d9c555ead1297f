#pragma once
// One localization run over a robot log, and the error metrics of spec §4.
//
//   const RobotLog log = robot::carpark_to_log(robot::load_carpark(dir), model);
//   const LocalizationProblem problem = make_problem(log, model.dt());
//   LocalizationRun run = run_localization(problem, model, sensor, ImplicitProposal{}, options);
//   LocalizationMetrics m = localization_metrics(run, problem.truth);
//
// The run records, per motion step, the posterior summary of the engine and the wall time of the
// step; the metrics compare the weighted means with the ground truth where it is defined.

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <vector>

#include "implicit/filter/particle_filter.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::filter {

/// A log prepared for filtering: steps, detections per step (map indices), truth per step.
struct LocalizationProblem {
  robot::LandmarkMap map;
  Pose initial_mean = Pose::Zero();
  Mat3 initial_covariance = Mat3::Identity();
  robot::StepSchedule schedule;
  std::vector<std::vector<LabelledMeasurement>> detections;  ///< per step (empty: predict only)
  robot::TruthTrack truth;
  int detections_total = 0;
};

/// Builds the problem from a log with an `initial` record; scans are attached to the nearest step
/// within dt / 2. Throws InvalidArgument when the log has no initial pose, no controls or no map.
LocalizationProblem make_problem(const robot::RobotLog& log, double dt);

struct LocalizationRun {
  std::vector<StepSummary> steps;
  double seconds = 0.0;      ///< wall time of the filter loop (initialisation excluded)
  double cpu_seconds = 0.0;  ///< process CPU time of the loop (all threads; = wall when idle-free)
  int resamplings = 0;
};

/// CPU time of the process [s] (all threads), for "CPU time per step" figures.
inline double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

template <robot::MotionModel Motion, robot::LandmarkSensor Sensor, typename Proposal>
LocalizationRun run_localization(const LocalizationProblem& problem, const Motion& motion,
                                 const Sensor& sensor, const Proposal& proposal,
                                 const FilterOptions& options) {
  ParticleFilter pf(motion, sensor, problem.map, proposal, options);
  pf.initialize(problem.initial_mean, problem.initial_covariance);
  LocalizationRun run;
  run.steps.reserve(problem.schedule.steps.size());
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  for (std::size_t n = 0; n < problem.schedule.steps.size(); ++n) {
    run.steps.push_back(pf.step(problem.schedule.steps[n].u, problem.detections[n]));
    run.resamplings += run.steps.back().resampled ? 1 : 0;
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpu_seconds = process_cpu_seconds() - cpu_start;
  return run;
}

struct LocalizationMetrics {
  double error_percent = 0.0;  ///< paper metric: 100 |p_hat - p| / |p| over all steps with truth
  double rmse = 0.0;           ///< position RMSE [m]
  double max_error = 0.0;      ///< [m]
  double heading_rmse = std::numeric_limits<double>::quiet_NaN();  ///< where truth has a heading
  double ess_fraction = 0.0;                                       ///< mean ESS/M over update steps
  double detections_used = 0.0;     ///< sum over steps of the per-particle mean
  double detections_dropped = 0.0;  ///< idem
  double newton_evaluations = 0.0;  ///< mean per particle per update step
  double min_log_likelihood_increment = 0.0;
  int fallbacks = 0;
  int failures = 0;
};

/// Metrics of one run against the truth; `particles` is M (for ESS/M).
LocalizationMetrics localization_metrics(const LocalizationRun& run, const robot::TruthTrack& truth,
                                         std::size_t particles);

/// The same position metrics for any trajectory (e.g. dead reckoning).
double error_percent(const std::vector<Pose>& estimate, const robot::TruthTrack& truth);

}  // namespace implicit::filter
