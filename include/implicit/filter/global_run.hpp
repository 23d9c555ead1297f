#pragma once
// Localization without a known start pose, and recovery after kidnapping (spec §3.11).
//
//   GlobalOptions g;                       // source: kMixture (implicit) or kUniform (bootstrap)
//   g.start_time = 20.0;                   // ignore the data before
//   LocalizationRun run = run_global_localization(problem, model, sensor, ImplicitProposal{},
//                                                 options, g);
//   GlobalMetrics m = global_metrics(run, problem, g.start_time);  // scored from the start
//
// The run starts at the first step (at or after start_time) whose scan has at least
// g.init.min_detections detections (the mixture: and an isolated minimum of -log p(z | x)): its
// particles are an exact importance sample of u(x) p(z | x), u uniform over the map's bounds and
// all headings, drawn either from u itself (the bootstrap's uniform cloud, weighted by the
// likelihood) or from the mixture over the minima of F(x) = -log p(z | x)
// (global_localization.hpp). From the next step on it is the usual filter. With
// options.recovery.enabled the same source feeds recovery's injections (recovery.hpp).

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "implicit/filter/global_localization.hpp"
#include "implicit/filter/localization.hpp"

namespace implicit::filter {

enum class GlobalSource {
  kUniform,  ///< uniform over the bounds and headings: the AMCL way
  kMixture,  ///< the Gaussian mixture over the minima of -log p(z | x)
};

struct GlobalOptions {
  GlobalSource source = GlobalSource::kMixture;
  GlobalInitOptions init;  ///< the multi-start's cover and the bounds' margin
  double start_time = -std::numeric_limits<double>::infinity();  ///< [s] earlier data ignored
  bool global_start = true;  ///< false: start from the problem's initial pose (kidnapping runs)
  /// Defensive share of uniform draws in the mixture source: with clutter, every detection's
  /// likelihood is at least p0, so u(x) p(z | x) has a floor over the whole box that the modes do
  /// not cover; the uniform share keeps the weights' variance finite there.
  double uniform_fraction = 0.1;
};

/// Recovery's source (recovery.hpp) over the pose box: uniform, or the mixture over the minima of
/// -log p(z | x) for the current detections (found once per step in prepare()). Ctx is the
/// filter's Context on landmark detections (its z: robot::LandmarkDetections).
template <typename Ctx>
class PoseRecoverySource : public RecoverySource<Ctx> {
 public:
  PoseRecoverySource(GlobalSource source, PoseBounds bounds, GlobalInitOptions init,
                     double uniform_fraction)
      : source_(source), bounds_(bounds), init_(init), uniform_fraction_(uniform_fraction) {}

  bool prepare(const Ctx& ctx) override {
    sampler_.reset();
    if (source_ == GlobalSource::kUniform) return true;
    std::vector<Laplace<3>> modes = find_pose_modes(*ctx.z, bounds_, init_);
    if (modes.empty()) return false;  // e.g. one detection: F has no isolated minimum
    sampler_.emplace(std::move(modes), bounds_, uniform_fraction_);
    return true;
  }

  double draw(const Ctx& ctx, Rng& rng, Pose& x) const override {
    if (source_ == GlobalSource::kUniform) {
      x = uniform_pose(bounds_, rng);
      return ctx.observation->log_likelihood(*ctx.z, x);  // log u - log g = 0
    }
    return sampler_->draw(*ctx.z, rng, x);
  }

 private:
  GlobalSource source_;
  PoseBounds bounds_;
  GlobalInitOptions init_;
  double uniform_fraction_;
  std::optional<PoseMixtureSampler> sampler_;
};

/// See the top of the file. run.first_step is the problem's step of run.steps[0].
template <robot::MotionModel Motion, robot::LandmarkSensor Sensor, typename Proposal>
LocalizationRun run_global_localization(const LocalizationProblem& problem, const Motion& motion,
                                        const Sensor& sensor, const Proposal& proposal,
                                        const FilterOptions& options, const GlobalOptions& g) {
  const std::size_t steps = problem.schedule.steps.size();
  std::size_t first = 0;
  while (first < steps && problem.schedule.steps[first].time < g.start_time - 1e-9) ++first;
  if (g.global_start)
    while (first < steps &&
           problem.detections[first].size() < static_cast<std::size_t>(g.init.min_detections))
      ++first;
  require(first < steps,
          "global localization: no step at or after {} s has a scan with at least {} detections",
          g.start_time, g.init.min_detections);
  ParticleFilter pf(motion, sensor, problem.map, proposal, options);
  using Ctx = typename decltype(pf)::Context;
  const PoseBounds bounds = map_bounds(problem.map.positions(), g.init.margin);
  if (options.recovery.enabled)
    pf.set_recovery_source(
        std::make_shared<PoseRecoverySource<Ctx>>(g.source, bounds, g.init, g.uniform_fraction));
  LocalizationRun run;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  std::vector<Laplace<3>> modes;
  if (g.global_start && g.source == GlobalSource::kMixture) {
    // The mixture waits for the first scan with an isolated minimum (with two detections, one
    // of them clutter, there may be none); the run's clock starts at start_time all the same.
    for (std::size_t n = first; n < steps && modes.empty(); ++n) {
      if (problem.detections[n].size() < static_cast<std::size_t>(g.init.min_detections)) continue;
      modes = find_pose_modes(pf.context(problem.detections[n]), bounds, g.init);
      if (!modes.empty()) first = n;
    }
  }
  run.first_step = first;
  run.steps.reserve(steps - first);
  if (g.global_start) {
    // The first scan's particles: an importance sample of u(x) p(z | x).
    const auto d = pf.context(problem.detections[first]);
    std::vector<Pose> x(options.particles);
    std::vector<double> lw(options.particles);
    if (modes.empty()) {
      // The uniform cloud; also the mixture's fallback when no scan of the log has an isolated
      // minimum: still an exact sample, only a less efficient one.
      run.uniform_start = g.source == GlobalSource::kMixture;
      sample_uniform_poses(bounds, options.seed, x);
      parallel_for(x.size(), [&](std::size_t j) { lw[j] = d.model->log_likelihood(d, x[j]); });
    } else {
      sample_pose_mixture(d, modes, bounds, options.seed, first, x, lw, g.uniform_fraction);
    }
    pf.initialize(x, lw);
    run.steps.push_back(pf.last());  // the first scan's particles are its summary
    ++first;
  } else {
    pf.initialize(problem.initial_mean, problem.initial_covariance);
  }
  detail::step_through(pf, problem, first, run);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpu_seconds = process_cpu_seconds() - cpu_start;
  return run;
}

/// When a run counts as localized (spec §3.11).
struct GlobalCriteria {
  double threshold = 1.0;  ///< [m] position error
  double settle = 30.0;    ///< [s] after the start (or the end of a kidnapping gap)
};

struct GlobalMetrics {
  /// The position RMSE over the steps from `settle` seconds after `from` to the end is below
  /// `threshold`.
  bool success = false;
  double rmse_after_settle = std::numeric_limits<double>::quiet_NaN();  ///< [m]
  /// Seconds from `from` to the first step from which the error stays below `threshold` for
  /// 5 s; NaN if never.
  double time_to_converge = std::numeric_limits<double>::quiet_NaN();
  double particles_mean = 0.0;  ///< over the run's steps
  double particles_peak = 0.0;
  int injected = 0;  ///< particles drawn by recovery, all steps
};

/// Metrics of a run from time `from` (the start, or the end of a kidnapping gap) against the
/// problem's truth (steps without truth are skipped).
GlobalMetrics global_metrics(const LocalizationRun& run, const LocalizationProblem& problem,
                             double from, const GlobalCriteria& criteria = {});

}  // namespace implicit::filter
