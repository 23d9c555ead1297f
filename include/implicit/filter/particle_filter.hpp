#pragma once
// Monte Carlo localization: the generic engine (particle_engine.hpp) with a pose as the particle,
// proposals as plug-ins (proposals.hpp) and the pose collector (pose_moments.hpp).
//
//   using namespace implicit;
//   filter::ParticleFilter pf(robot::UteModel(), robot::RangeBearingSensor(), map,
//                             filter::ImplicitProposal{}, options);  // FilterOptions
//   pf.initialize(mean, covariance);
//   for (const auto& step : steps) {
//     const filter::StepSummary& s = pf.step(step.u, detections);   // detections may be empty
//     ... s.mean, s.covariance, s.ess, s.resampled, s.log_likelihood_increment ...
//   }
//
// Each step moves every particle with the proposal (in parallel; particle j draws from
// Rng({seed, step, j, proposal purpose}), so results are bit-identical for any thread count),
// adds the log weight increments, normalises (log-sum-exp), and resamples (systematic by default)
// when ESS < threshold * M. Steps without detections only predict; the weights stay unchanged.
//
// Per-step outputs: weighted mean pose (heading by circular mean), covariance (heading deviations
// wrapped), ESS, whether it resampled, and the log marginal-likelihood increment
// log sum_j wbar^j_{n-1} exp(delta l^j) - a "lost" signal: it drops sharply when no particle
// explains the data. ESS alone is not a health signal (it can be high in a lost filter).
//
// Common mistakes: reusing one Rng stream for two purposes (use distinct purposes), reading the
// heading mean as the plain average of angles (use StepSummary::mean), and comparing
// log-likelihood increments between runs with different clutter settings.

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/kld.hpp"
#include "implicit/filter/particle_engine.hpp"
#include "implicit/filter/pose_moments.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/filter/recovery.hpp"
#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

struct FilterOptions {
  std::size_t particles = 100;
  double resample_threshold = 0.5;  ///< resample when ESS < threshold * M
  ResamplingScheme resampling = ResamplingScheme::kSystematic;
  std::uint64_t seed = 0;  ///< first field of every stream key
  AssociationOptions association;
  /// Adaptive particle count: at every update step resample to the KLD bound (kld.hpp). The
  /// first count is `particles`.
  KldOptions kld;
  /// Injection of particles from a recovery source when the filter looks lost (recovery.hpp);
  /// needs set_recovery_source().
  RecoveryOptions recovery;
};

struct StepSummary {
  std::size_t step = 0;  ///< 1-based step counter
  Pose mean = Pose::Zero();
  Mat3 covariance = Mat3::Zero();
  double ess = 0.0;  ///< at update steps: after weighting, before any resampling
  bool resampled = false;
  bool updated = false;                   ///< detections were processed at this step
  double log_likelihood_increment = 0.0;  ///< 0 at prediction-only steps
  bool all_weights_zero = false;          ///< every particle got weight 0: weights reset to uniform
  double detections_used = 0.0;        ///< mean over particles (weighted by the previous weights)
  double detections_dropped = 0.0;     ///< idem
  double newton_evaluations = 0.0;     ///< mean over particles
  int fallbacks = 0;                   ///< particles that needed a Cholesky fallback
  int failures = 0;                    ///< particles with a non-finite model output (weight 0)
  std::size_t particles = 0;           ///< particles after this step (varies under KLD-sampling)
  double injection_probability = 0.0;  ///< recovery: the fraction drawn from the source
  int injected = 0;                    ///< recovery: particles drawn from the source
};

/// A direct measurement of the state's position (x, y) ~ N(position, std^2 I): a GPS fix. The
/// proposals do not see it; it multiplies each particle's weight by its likelihood after the
/// proposal (valid importance sampling: the target gains the factor, the proposal is unchanged).
/// Used for the GPS-aided reference run that can serve as ground truth (paper §4.1).
struct PositionFix {
  Vec<2> position = Vec<2>::Zero();
  double std = 0.5;  ///< [m]
};

template <robot::MotionModel Motion, robot::LandmarkSensor Sensor, typename Proposal>
class ParticleFilter {
 public:
  ParticleFilter(Motion motion, Sensor sensor, robot::LandmarkMap map, Proposal proposal,
                 FilterOptions options)
      : motion_(std::move(motion)),
        step_motion_(motion_),
        sensor_(std::move(sensor)),
        map_(std::move(map)),
        proposal_(std::move(proposal)),
        options_(options) {
    require(options_.particles >= 1, "particle filter: expected at least 1 particle, got {}",
            options_.particles);
    require(options_.resample_threshold >= 0 && options_.resample_threshold <= 1,
            "particle filter: expected a resampling threshold in [0, 1], got {}",
            options_.resample_threshold);
    require(options_.association.gate > 0, "particle filter: expected a positive gate, got {}",
            options_.association.gate);
    const Mat2& noise = sensor_.noise_covariance();
    Eigen::LLT<Mat2> llt(noise);
    require(llt.info() == Eigen::Success && noise.allFinite(),
            "particle filter: expected a symmetric positive definite sensor covariance, got "
            "[[{}, {}], [{}, {}]]",
            noise(0, 0), noise(0, 1), noise(1, 0), noise(1, 1));
    context_.motion = &step_motion_;
    context_.sensor = &sensor_;
    context_.map = std::span<const Landmark>(map_.positions());
    context_.noise_information = llt.solve(Mat2::Identity());
    context_.log_det_noise = 2.0 * std::log(llt.matrixL()(0, 0) * llt.matrixL()(1, 1));
    context_.log_clutter = robot::clutter_log_density(options_.association.gate, noise);
    context_.association = options_.association;
    if (options_.kld.enabled) validate(options_.kld);
    if (options_.recovery.enabled) validate(options_.recovery);
    resize(options_.particles);
  }

  using Context = ProposalContext<Motion, Sensor>;

  /// The source of recovery's injected particles (used when options().recovery.enabled).
  void set_recovery_source(std::shared_ptr<RecoverySource<Context>> source) {
    recovery_source_ = std::move(source);
  }
  /// What the proposals see at a step with detections z and no control (for a global
  /// initialisation, which samples the pose from the detections alone). Valid while z lives.
  Context context(std::span<const LabelledMeasurement> z) const {
    Context c = context_;
    c.motion = &step_motion_;
    c.sensor = &sensor_;
    c.map = std::span<const Landmark>(map_.positions());
    c.u = Control::Zero();
    c.z = z;
    return c;
  }

  /// The lost signal's averages (recovery.hpp).
  const LikelihoodAverages& likelihood_averages() const { return averages_; }

  const Motion& motion() const { return motion_; }
  const Sensor& sensor() const { return sensor_; }
  const robot::LandmarkMap& map() const { return map_; }
  const FilterOptions& options() const { return options_; }
  std::size_t size() const { return engine_.size(); }
  std::span<const Pose> particles() const { return engine_.particles(); }
  std::span<const double> weights() const { return engine_.weights(); }  ///< normalised
  const StepSummary& last() const { return summary_; }

  /// Draws the particles from N(mean, covariance) (stream step 0, purpose kInitial).
  void initialize(const Pose& mean, const Mat3& covariance) {
    Eigen::LLT<Mat3> llt(covariance);
    require(llt.info() == Eigen::Success && covariance.allFinite(),
            "particle filter: expected a symmetric positive definite initial covariance");
    const Mat3 l = llt.matrixL();
    engine_.generate([&](std::size_t j) -> Pose {
      Rng rng({options_.seed, 0, j, purpose::kInitial});
      const Vec<3> xi = rng.normal_vector<3>();  // one call: argument order is unspecified
      return mean + l * xi;
    });
    step_ = 0;
    averages_.reset();  // a new start: the lost signal's history belongs to the old one
    summarize();
  }

  /// Starts from given particles with equal weights.
  void initialize(std::span<const Pose> particles) {
    require(particles.size() == engine_.size(),
            "particle filter: expected {} initial particles, got {}", engine_.size(),
            particles.size());
    engine_.assign(particles);
    step_ = 0;
    averages_.reset();
    summarize();
  }

  /// Starts from weighted particles (log weights, not necessarily normalised), e.g. an importance
  /// sample of a global initialisation; the particle count becomes particles.size().
  void initialize(std::span<const Pose> particles, std::span<const double> log_weights) {
    engine_.assign(particles, log_weights);
    resize_scratch(particles.size());
    step_ = 0;
    averages_.reset();
    summarize();
  }

  /// The length of the following steps [s] (the data's own time stamps; until called, the
  /// model's dt()). A model without with_dt() accepts only its own dt (within 1e-9 s).
  void set_step_length(double dt) {
    require(dt > 0 && std::isfinite(dt), "particle filter: expected a positive step length, got {}",
            dt);
    if constexpr (robot::VariableStepMotionModel<Motion>) {
      step_motion_ = motion_.with_dt(dt);
    } else {
      require(std::abs(dt - motion_.dt()) <= 1e-9,
              "particle filter: expected steps of the motion model's fixed length {} s (it has "
              "no with_dt()), got a step of {} s",
              motion_.dt(), dt);
    }
  }

  /// One motion step with control u and the detections seen after it (empty: predict only).
  const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z = {}) {
    return step_impl(u, z, nullptr);
  }

  /// A step that also weights by a position fix (GPS) of the new state.
  const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z,
                          const PositionFix& fix) {
    require(fix.position.allFinite() && fix.std > 0 && std::isfinite(fix.std),
            "particle filter: expected a finite position fix with a positive std, got ({}, {}) "
            "std {}",
            fix.position(0), fix.position(1), fix.std);
    return step_impl(u, z, &fix);
  }

 private:
  const StepSummary& step_impl(const Control& u, std::span<const LabelledMeasurement> z,
                               const PositionFix* fix) {
    require(z.size() <= static_cast<std::size_t>(MclObjective<Sensor>::kMaxTerms),
            "particle filter: expected at most {} detections per step, got {}",
            MclObjective<Sensor>::kMaxTerms, z.size());
    for (const LabelledMeasurement& lz : z)
      require(lz.landmark < static_cast<int>(map_.size()) && lz.z.allFinite(),
              "particle filter: expected finite detections with a landmark index below {}, got "
              "({}, {}) for landmark {}",
              map_.size(), lz.z(0), lz.z(1), lz.landmark);
    ++step_;
    context_.motion = &step_motion_;  // refreshed: the filter may have been moved since then
    context_.sensor = &sensor_;
    context_.map = std::span<const Landmark>(map_.positions());
    context_.u = u;
    context_.z = z;
    const std::uint64_t n = step_;
    const double p = injection_probability(z);
    std::vector<char>& injected = injected_;
    engine_.move([&](std::size_t j, Pose& x) {
      stats_[j] = ParticleStats{};
      injected[j] = 0;
      const Pose previous = x;
      if (p > 0.0) {
        // The choice has its own stream: the proposal's draws do not depend on it.
        Rng choice({options_.seed, n, j, purpose::kRecovery});
        if (choice.uniform() < p) {
          injected[j] = 1;
          return injected_log_weight_ + recovery_source_->draw(context_, choice, x);
        }
      }
      Rng rng({options_.seed, n, j, Proposal::kPurpose});
      return proposal_.propose(context_, previous, rng, x, stats_[j]) + kept_log_weight_;
    });
    if (fix) {
      // The fix multiplies the target, not the proposal: valid importance sampling.
      const double info = 1.0 / (fix->std * fix->std);
      const double norm = -kLog2Pi - 2.0 * std::log(fix->std);  // log N(0; 0, std^2 I)
      const std::span<const Pose> xs = engine_.particles();
      const std::span<double> inc = engine_.increments();
      for (std::size_t j = 0; j < xs.size(); ++j)
        inc[j] += norm - 0.5 * info * (xs[j].template head<2>() - fix->position).squaredNorm();
    }

    summary_ = StepSummary{};
    summary_.step = step_;
    summary_.updated = !z.empty() || fix != nullptr;
    const std::span<const double> w = engine_.weights();
    for (std::size_t j = 0; j < stats_.size(); ++j) {
      summary_.detections_used += w[j] * stats_[j].used;
      summary_.detections_dropped += w[j] * stats_[j].dropped;
      summary_.newton_evaluations += stats_[j].iterations;
      summary_.fallbacks += stats_[j].fallback ? 1 : 0;
      summary_.failures += stats_[j].failed ? 1 : 0;
    }
    summary_.newton_evaluations /= static_cast<double>(stats_.size());
    summary_.injection_probability = p;
    for (char c : injected) summary_.injected += c;
    if (summary_.updated || summary_.failures > 0) update_weights();
    if (options_.recovery.enabled) {
      // With p = 0 the factor 1 - epsilon of the motion branch is common to all particles and
      // was left out of the weights (bit-identical to a filter without recovery); it belongs to
      // the likelihood of the data all the same.
      if (p == 0.0 && !z.empty())
        summary_.log_likelihood_increment += std::log1p(-options_.recovery.kidnap_probability);
      averages_.update(summary_.log_likelihood_increment, static_cast<int>(z.size()),
                       options_.recovery);
    }
    summarize();
    return summary_;
  }

  /// The fraction of this step's particles drawn from the recovery source (0 without one, or
  /// without detections to weight them by), and the log weight factors of both branches.
  double injection_probability(std::span<const LabelledMeasurement> z) {
    injected_log_weight_ = kept_log_weight_ = 0.0;
    if (!options_.recovery.enabled || !recovery_source_ || z.empty()) return 0.0;
    const double p = averages_.injection_probability(options_.recovery);
    if (!(p > 0.0) || !recovery_source_->prepare(context_)) return 0.0;
    const double eps = options_.recovery.kidnap_probability;
    injected_log_weight_ = std::log(eps) - std::log(p);
    kept_log_weight_ = std::log1p(-eps) - std::log1p(-p);
    return p;
  }

  void resize(std::size_t m) {
    engine_.assign(m, Pose::Zero());
    resize_scratch(m);
  }

  /// The per-particle scratch for m particles.
  void resize_scratch(std::size_t m) {
    stats_.resize(m);
    injected_.resize(m);
  }

  void update_weights() {
    const Reweighting r = engine_.reweight();
    summary_.log_likelihood_increment = r.log_likelihood_increment;
    summary_.all_weights_zero = r.all_weights_zero;
    summary_.ess = r.ess;  // before resampling: the quality of this update's weights
    const std::size_t m = engine_.size();
    if (options_.kld.enabled) {
      // KLD-sampling draws as many ancestors as the occupied bins call for, at every update.
      Rng rng({options_.seed, step_, 0, purpose::kResampling});
      engine_.resample(kld_resample(engine_.weights(), engine_.particles(), options_.kld, rng));
      resize_scratch(engine_.size());
      summary_.resampled = true;
    } else if (needs_resampling(r.ess, m, options_.resample_threshold)) {
      Rng rng({options_.seed, step_, 0, purpose::kResampling});
      engine_.resample(resample(options_.resampling, engine_.weights(), m, rng));
      summary_.resampled = true;
    }
  }

  void summarize() {
    const auto& moments = pose_moments_(engine_.particles(), engine_.weights(),
                                        [](const Pose& x) -> const Pose& { return x; });
    summary_.mean = moments.mean;
    summary_.covariance = moments.covariance;
    summary_.particles = engine_.size();
    if (!summary_.updated) summary_.ess = effective_sample_size(engine_.weights());
  }

  Motion motion_;
  Motion step_motion_;  ///< motion_ for the current step length
  Sensor sensor_;
  robot::LandmarkMap map_;
  Proposal proposal_;
  FilterOptions options_;
  ProposalContext<Motion, Sensor> context_;
  ParticleEngine<Pose> engine_;
  PoseMoments pose_moments_;  ///< the estimate (the collector keeps its scratch)
  std::vector<ParticleStats> stats_;
  std::vector<char> injected_;  ///< per particle: drawn from the recovery source this step
  std::shared_ptr<RecoverySource<Context>> recovery_source_;
  LikelihoodAverages averages_;
  double injected_log_weight_ = 0.0, kept_log_weight_ = 0.0;  ///< log(eps/p), log((1-eps)/(1-p))
  std::uint64_t step_ = 0;
  StepSummary summary_;
};

}  // namespace implicit::filter
