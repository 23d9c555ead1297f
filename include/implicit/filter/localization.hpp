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
  /// Per step: its length [s], the time since the previous control (the first step: since the
  /// control before it, else since the initial time). Within 1e-9 s of the model's dt it is that
  /// dt exactly (time stamps are printed with finite precision).
  std::vector<double> step_dt;
  std::vector<std::vector<LabelledMeasurement>> detections;  ///< per step (empty: predict only)
  robot::TruthTrack truth;
  int detections_total = 0;
  /// Per step: the truth record (e.g. a GPS fix) nearest in time within dt / 2, NaN where none.
  /// The measurements of the GPS-aided reference run (reference_track).
  std::vector<Vec<2>> position_fixes;
};

/// Builds the problem from a log with an `initial` record; scans are attached to the nearest step
/// within dt / 2 (dt: the model's nominal step). Throws InvalidArgument when the log has no
/// initial pose, no controls or no map, or when a detection names a landmark id not in the map.
LocalizationProblem make_problem(const robot::RobotLog& log, double dt);

/// The problem without the steps whose time is in [from, to): their controls and detections are
/// never seen, and the step after the gap keeps its own length, so the filter's pose goes wrong
/// without being told ("kidnapping" by lost odometry). Also used to start a run at a later time
/// (from = -inf). Truth and fixes are dropped with their steps. Throws if no step is left.
LocalizationProblem without_steps(const LocalizationProblem& problem, double from, double to);

struct LocalizationRun {
  std::vector<StepSummary> steps;
  std::size_t first_step = 0;  ///< the problem's step of steps[0] (a run may start later)
  bool uniform_start = false;  ///< a global start's mixture found no pose: uniform cloud instead
  double seconds = 0.0;        ///< wall time of the filter loop (initialisation excluded)
  double cpu_seconds = 0.0;  ///< process CPU time of the loop (all threads; = wall when idle-free)
  int resamplings = 0;
};

/// How the GPS-aided reference run is made (see reference_track).
struct ReferenceOptions {
  double gps_std = 0.5;          ///< [m] std of each coordinate of a fix
  std::size_t particles = 5000;  ///< large, so that its Monte Carlo error is negligible
  std::uint64_t seed = 1;        ///< fixed: the reference does not change with the runs' seed
};

/// CPU time of the process [s] (all threads), for "CPU time per step" figures.
inline double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

namespace detail {

/// Steps `pf` through the problem's steps from `first` on, each with its own length, recording
/// every summary in `run`.
template <typename Filter>
void step_through(Filter& pf, const LocalizationProblem& problem, std::size_t first,
                  LocalizationRun& run) {
  for (std::size_t n = first; n < problem.schedule.steps.size(); ++n) {
    if (!problem.step_dt.empty()) pf.set_step_length(problem.step_dt[n]);
    run.steps.push_back(pf.step(problem.schedule.steps[n].u, problem.detections[n]));
    run.resamplings += run.steps.back().resampled ? 1 : 0;
  }
}

}  // namespace detail

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
  detail::step_through(pf, problem, 0, run);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpu_seconds = process_cpu_seconds() - cpu_start;
  return run;
}

/// The paper's alternative ground truth (§4.1): an MCL run that ALSO weights by the position
/// fixes of the problem (GPS, N(fix; position, gps_std^2 I)) with many particles; its weighted-mean
/// path (heading: circular mean) is returned as a truth track for every step. Fusing the beacons
/// and the fixes through the motion model, it is closer to the true path than the fixes alone.
template <robot::MotionModel Motion, robot::LandmarkSensor Sensor, typename Proposal>
robot::TruthTrack reference_track(const LocalizationProblem& problem, const Motion& motion,
                                  const Sensor& sensor, const Proposal& proposal,
                                  const ReferenceOptions& reference, FilterOptions options = {}) {
  require(reference.gps_std > 0 && std::isfinite(reference.gps_std),
          "reference track: expected a positive GPS std, got {}", reference.gps_std);
  require(problem.position_fixes.size() == problem.schedule.steps.size(),
          "reference track: expected {} position fixes (one per step, NaN for none), got {}",
          problem.schedule.steps.size(), problem.position_fixes.size());
  options.particles = reference.particles;
  options.seed = reference.seed;
  ParticleFilter pf(motion, sensor, problem.map, proposal, options);
  pf.initialize(problem.initial_mean, problem.initial_covariance);
  robot::TruthTrack track;
  track.position.reserve(problem.schedule.steps.size());
  track.heading.reserve(problem.schedule.steps.size());
  for (std::size_t n = 0; n < problem.schedule.steps.size(); ++n) {
    if (!problem.step_dt.empty()) pf.set_step_length(problem.step_dt[n]);
    const Vec<2>& fix = problem.position_fixes[n];
    const StepSummary& s = fix.allFinite()
                               ? pf.step(problem.schedule.steps[n].u, problem.detections[n],
                                         PositionFix{fix, reference.gps_std})
                               : pf.step(problem.schedule.steps[n].u, problem.detections[n]);
    track.position.push_back(s.mean.head<2>());
    track.heading.push_back(s.mean(2));
  }
  return track;
}

struct LocalizationMetrics {
  double error_percent = 0.0;  ///< paper metric: 100 |p_hat - p| / |p| over all steps with truth
  double rmse = 0.0;           ///< position RMSE [m]
  double max_error = 0.0;      ///< [m]
  double heading_rmse = std::numeric_limits<double>::quiet_NaN();  ///< where truth has a heading
  double ess_fraction = 0.0;                                       ///< mean ESS/M over update steps
  double detections_used = 0.0;     ///< sum over steps of the per-particle mean
  double detections_dropped = 0.0;  ///< idem
  int gated = 0;  ///< labelled detections left out by the prediction gate (StepSummary::gated)
  double newton_evaluations = 0.0;  ///< mean per particle per update step
  double min_log_likelihood_increment = 0.0;
  int fallbacks = 0;
  int failures = 0;
};

/// Metrics of one run against the truth; `particles` is M (for ESS/M). Without any step with
/// truth the position metrics (error_percent, rmse, max_error) are NaN: nothing was scored.
LocalizationMetrics localization_metrics(const LocalizationRun& run, const robot::TruthTrack& truth,
                                         std::size_t particles);

/// The same position metrics for any trajectory (e.g. dead reckoning).
double error_percent(const std::vector<Pose>& estimate, const robot::TruthTrack& truth);

}  // namespace implicit::filter
