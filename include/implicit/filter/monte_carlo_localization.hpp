#pragma once
// Monte Carlo localization on any observation model (robot/observation_model.hpp): landmark
// detections (robot/landmark_observation.hpp; particle_filter.hpp names this filter with it), a
// laser scan against an occupancy grid (robot/likelihood_field.hpp), or a sensor of your own. The
// engine (particle_engine.hpp), the proposals (proposals.hpp: bootstrap and implicit),
// KLD-sampling (kld.hpp) and recovery (recovery.hpp) are the same for all of them.
//
//   using namespace implicit;
//   robot::LikelihoodFieldModel laser(field, robot::LikelihoodFieldParams{}, mount);
//   filter::MonteCarloLocalization pf(robot::OdometryModel(alphas), laser,
//                                     filter::ImplicitProposal{}, options);   // FilterOptions
//   pf.initialize(mean, covariance);
//   for (...) {
//     pf.step(odometry_increment);                       // prediction only
//     const filter::StepSummary& s = pf.step(odometry_increment, scan);   // with an observation
//   }
//
// Each step prepares the observation once (the model's prepare(): validation, beam selection),
// then moves every particle with the proposal in parallel; particle j draws from
// Rng({seed, step, j, purpose}), so results are bit-identical for any thread count. Weights are
// normalised in the log domain; the filter resamples when ESS < threshold * M (or at every
// update under KLD-sampling). A step may also weight by a PositionFix (GPS) of the new state.
//
// Per-step outputs (StepSummary): weighted mean pose (heading by circular mean), covariance
// (heading deviations wrapped), ESS, whether it resampled, and the log marginal-likelihood
// increment log sum_j wbar^j_{n-1} exp(delta l^j) - a "lost" signal: it drops sharply when no
// particle explains the data. ESS alone is not a health signal (it can be high in a lost filter).
//
// The implicit proposal needs the model's derivatives: a model that is not differentiable (e.g.
// the likelihood field with nav2's cubed-sum aggregation) is refused at construction, with the
// model's reason.
//
// Common mistakes: reusing one Rng stream for two purposes (use distinct purposes), reading the
// heading mean as the plain average of angles (use StepSummary::mean), and comparing
// log-likelihood increments between runs with different clutter settings.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/filter_options.hpp"
#include "implicit/filter/kld.hpp"
#include "implicit/filter/particle_engine.hpp"
#include "implicit/filter/pose_moments.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/filter/recovery.hpp"
#include "implicit/robot/observation_model.hpp"

namespace implicit::filter {

/// Whether a proposal uses the observation model's derivatives (it declares kNeedsDerivatives).
template <typename Proposal>
constexpr bool needs_derivatives() {
  if constexpr (requires { Proposal::kNeedsDerivatives; })
    return Proposal::kNeedsDerivatives;
  else
    return false;
}

namespace detail {
struct NoGateKept {};
template <typename O>
struct GateKeptOf {
  using type = NoGateKept;
};
template <typename O>
requires requires { typename O::GateKept; }
struct GateKeptOf<O> {
  using type = typename O::GateKept;
};
}  // namespace detail

/// What a prediction-gated observation model keeps of an observation (an empty type otherwise).
template <typename O>
using GateKeptOf = typename detail::GateKeptOf<O>::type;

template <robot::PoseMotionModel Motion, robot::ObservationModel Observation, typename Proposal>
class MonteCarloLocalization {
 public:
  using Control = robot::ControlOf<Motion>;
  using Prepared = typename Observation::Prepared;
  using Context = ObservationContext<Motion, Observation>;

  MonteCarloLocalization(Motion motion, Observation observation, Proposal proposal,
                         FilterOptions options)
      : motion_(std::move(motion)),
        step_motion_(motion_),
        observation_(std::move(observation)),
        proposal_(std::move(proposal)),
        options_(options) {
    require(options_.particles >= 1, "particle filter: expected at least 1 particle, got {}",
            options_.particles);
    require(options_.resample_threshold >= 0 && options_.resample_threshold <= 1,
            "particle filter: expected a resampling threshold in [0, 1], got {}",
            options_.resample_threshold);
    if constexpr (needs_derivatives<Proposal>()) {
      static_assert(robot::DifferentiableObservationModel<Observation>,
                    "this proposal needs an observation model with derivatives");
      require(observation_.differentiable(),
              "particle filter: the {} proposal needs the observation model's derivatives, but "
              "{}",
              Proposal::kName, observation_.why_not_differentiable());
    }
    if (options_.kld.enabled) validate(options_.kld);
    if (options_.recovery.enabled) validate(options_.recovery);
    engine_.assign(options_.particles, robot::Pose::Zero());
    resize_scratch(options_.particles);
  }

  /// The source of recovery's injected particles (used when options().recovery.enabled).
  void set_recovery_source(std::shared_ptr<RecoverySource<Context>> source) {
    recovery_source_ = std::move(source);
  }

  const Motion& motion() const { return motion_; }
  const Observation& observation() const { return observation_; }
  const FilterOptions& options() const { return options_; }
  std::size_t size() const { return engine_.size(); }
  std::span<const robot::Pose> particles() const { return engine_.particles(); }
  std::span<const double> weights() const { return engine_.weights(); }  ///< normalised
  const StepSummary& last() const { return summary_; }
  const LikelihoodAverages& likelihood_averages() const { return averages_; }

  /// Draws the particles from N(mean, covariance) (stream step 0, purpose kInitial).
  void initialize(const robot::Pose& mean, const robot::Mat3& covariance) {
    require(mean.allFinite(), "particle filter: expected a finite initial mean");
    Eigen::LLT<robot::Mat3> llt(covariance);
    require(llt.info() == Eigen::Success && covariance.allFinite(),
            "particle filter: expected a symmetric positive definite initial covariance");
    const robot::Mat3 l = llt.matrixL();
    engine_.generate([&](std::size_t j) -> robot::Pose {
      Rng rng({options_.seed, 0, j, purpose::kInitial});
      const Vec<3> xi = rng.normal_vector<3>();
      return mean + l * xi;
    });
    restart();
  }

  /// Starts from given particles with equal weights (as many as the filter has).
  void initialize(std::span<const robot::Pose> particles) {
    require(particles.size() == engine_.size(),
            "particle filter: expected {} initial particles, got {}", engine_.size(),
            particles.size());
    engine_.assign(particles);
    restart();
  }

  /// Starts from weighted particles (log weights, any common offset), e.g. a global start; the
  /// particle count becomes particles.size().
  void initialize(std::span<const robot::Pose> particles, std::span<const double> log_weights) {
    engine_.assign(particles, log_weights);
    resize_scratch(particles.size());
    restart();
  }

  /// The length of the following steps [s] (the data's own time stamps; until called, the
  /// model's dt()). A model without with_dt() accepts only its own dt (within 1e-9 s).
  void set_step_length(double dt) requires robot::MotionModel<Motion> {
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

  /// The observation prepared as the model would at a step (for global starts and tools).
  Prepared prepare(const typename Observation::Observation& z, std::string_view where) const {
    return observation_.prepare(z, where);
  }

  /// One motion step with control u, no observation: the weights are unchanged.
  const StepSummary& step(const Control& u) { return step_impl(u, nullptr, 0, nullptr); }

  /// One motion step with control u and the observation seen after it; `where` names it in
  /// errors (e.g. the file and line).
  const StepSummary& step(const Control& u, const typename Observation::Observation& z,
                          std::string_view where = "observation") {
    return step_observed(u, z, where, nullptr);
  }

  /// The same step, also weighted by a position fix (GPS) of the new state.
  const StepSummary& step(const Control& u, const typename Observation::Observation& z,
                          const PositionFix& fix, std::string_view where = "observation") {
    validate(fix);
    return step_observed(u, z, where, &fix);
  }

  /// A step with an observation prepared by prepare().
  const StepSummary& step_prepared(const Control& u, const Prepared& z) {
    return step_impl(u, &z, observation_size(z), nullptr);
  }

  /// A step with an optional prepared observation (nullptr: none) that also weights by a
  /// position fix (GPS) of the new state (nullptr: none).
  const StepSummary& step_prepared(const Control& u, const Prepared* z, const PositionFix* fix) {
    if (fix) validate(*fix);
    return step_impl(u, z, z ? observation_size(*z) : 0, fix);
  }

 private:
  /// A step with an observation: a prediction-gated model first checks it against the predicted
  /// pose distribution, and the step reads what it keeps (nothing kept: a prediction step).
  const StepSummary& step_observed(const Control& u, const typename Observation::Observation& z,
                                   std::string_view where, const PositionFix* fix) {
    int gated = 0;
    if constexpr (robot::PredictionGatedObservationModel<Observation>) {
      robot::Pose mean;
      robot::Mat3 cov;
      if (observation_.gate_needed(z) && predicted_moments(u, mean, cov))
        gated = observation_.gate(z, mean, cov, gate_kept_);
      if (gated > 0) {
        const typename Observation::Observation kept(gate_kept_);
        if (observation_size_of(kept) == 0) {
          step_impl(u, nullptr, 0, fix);
        } else {
          prepared_ = observation_.prepare(kept, where);
          step_impl(u, &prepared_, observation_size(prepared_), fix);
        }
        summary_.gated = gated;
        return summary_;
      }
    }
    prepared_ = observation_.prepare(z, where);
    return step_impl(u, &prepared_, observation_size(prepared_), fix);
  }

  template <typename Z>
  static std::size_t observation_size_of(const Z& z) {
    if constexpr (requires { z.size(); })
      return z.size();
    else
      return 1;
  }

  static int observation_size(const Prepared& z) {
    if constexpr (requires { z.size(); })
      return static_cast<int>(z.size());
    else
      return 1;
  }

  /// The predicted pose distribution at this step: the last posterior's mean and covariance
  /// (summary_) through the motion model by the unscented transform (six sigma points, weights
  /// 1/6, so no Jacobian of the motion model is needed), plus the mean process covariance. O(1)
  /// in the particle count. False when the covariance does not factor or a prediction fails.
  bool predicted_moments(const Control& u, robot::Pose& mean, robot::Mat3& cov) const {
    const Eigen::LLT<robot::Mat3> llt(summary_.covariance + 1e-12 * robot::Mat3::Identity());
    if (llt.info() != Eigen::Success || !summary_.mean.allFinite()) return false;
    const robot::Mat3 spread = std::sqrt(3.0) * robot::Mat3(llt.matrixL());
    robot::Pose centre, f[6];
    robot::Mat3 sigma1, process = robot::Mat3::Zero();
    SmallFactor<3> unused;
    detail::predict_pose(step_motion_, summary_.mean, u, centre, sigma1, unused);
    if (!centre.allFinite()) return false;
    Vec<3> sum = Vec<3>::Zero();
    for (int k = 0; k < 6; ++k) {
      const robot::Pose chi = summary_.mean + (k < 3 ? 1.0 : -1.0) * spread.col(k % 3);
      detail::predict_pose(step_motion_, chi, u, f[k], sigma1, unused);
      if (!f[k].allFinite() || !sigma1.allFinite()) return false;
      f[k](2) = centre(2) + wrap_angle(f[k](2) - centre(2));  // headings on the centre's branch
      sum += f[k];
      process += sigma1 / 6.0;
    }
    mean = sum / 6.0;
    cov = process;
    for (const robot::Pose& fk : f) cov.noalias() += (fk - mean) * (fk - mean).transpose() / 6.0;
    mean(2) = wrap_angle(mean(2));
    return true;
  }

  void restart() {
    step_ = 0;
    averages_.reset();
    summary_ = StepSummary{};
    summarize();
  }

  const StepSummary& step_impl(const Control& u, const Prepared* z, int terms,
                               const PositionFix* fix) {
    ++step_;
    context_.motion = &step_motion_;  // refreshed: the filter may have been moved since then
    context_.observation = &observation_;
    context_.u = u;
    context_.z = z;
    const std::uint64_t n = step_;
    const double p = injection_probability(z != nullptr);
    engine_.move([&](std::size_t j, robot::Pose& x) {
      stats_[j] = ParticleStats{};
      injected_[j] = 0;
      const robot::Pose previous = x;
      if (p > 0.0) {
        // The choice has its own stream: the proposal's draws do not depend on it.
        Rng choice({options_.seed, n, j, purpose::kRecovery});
        if (choice.uniform() < p) {
          injected_[j] = 1;
          return injected_log_weight_ + recovery_source_->draw(context_, choice, x);
        }
      }
      Rng rng({options_.seed, n, j, Proposal::kPurpose});
      return proposal_.propose(context_, previous, rng, x, stats_[j]) + kept_log_weight_;
    });
    if (fix) weight_by(*fix);
    summary_ = StepSummary{};
    summary_.step = step_;
    summary_.updated = z != nullptr || fix != nullptr;
    collect_stats(terms, p);
    if (summary_.updated || summary_.failures > 0) update_weights();
    if (options_.recovery.enabled && z != nullptr) {
      // With p = 0 the factor 1 - epsilon of the motion branch is common to all particles and
      // was left out of the weights (bit-identical to a filter without recovery); it belongs to
      // the likelihood of the data all the same.
      if (p == 0.0)
        summary_.log_likelihood_increment += std::log1p(-options_.recovery.kidnap_probability);
      averages_.update(summary_.log_likelihood_increment, std::max(terms, 1), options_.recovery);
    }
    summarize();
    return summary_;
  }

  /// The fix multiplies the target, not the proposal: valid importance sampling.
  void weight_by(const PositionFix& fix) {
    const double info = 1.0 / (fix.std * fix.std);
    const double norm =
        -gaussian_log_normaliser(2, 2.0 * std::log(fix.std));  // log N(0; 0, std^2 I)
    const std::span<const robot::Pose> xs = engine_.particles();
    const std::span<double> inc = engine_.increments();
    for (std::size_t j = 0; j < xs.size(); ++j)
      inc[j] += norm - 0.5 * info * (xs[j].template head<2>() - fix.position).squaredNorm();
  }

  /// The proposals' per-particle counts into the summary: a counting model's used and dropped
  /// parts weighted by the previous weights, else the observation's parts.
  void collect_stats(int terms, double p) {
    const std::span<const double> w = engine_.weights();
    for (std::size_t j = 0; j < stats_.size(); ++j) {
      if constexpr (robot::CountingObservationModel<Observation>) {
        summary_.detections_used += w[j] * stats_[j].used;
        summary_.detections_dropped += w[j] * stats_[j].dropped;
      }
      summary_.newton_evaluations += stats_[j].iterations;
      summary_.fallbacks += stats_[j].fallback ? 1 : 0;
      summary_.failures += stats_[j].failed ? 1 : 0;
    }
    summary_.newton_evaluations /= static_cast<double>(stats_.size());
    if constexpr (!robot::CountingObservationModel<Observation>) summary_.detections_used = terms;
    summary_.injection_probability = p;
    for (char c : injected_) summary_.injected += c;
  }

  /// The fraction of this step's particles drawn from the recovery source (0 without one, or
  /// without an observation to weight them by), and the log weight factors of both branches.
  double injection_probability(bool observed) {
    injected_log_weight_ = kept_log_weight_ = 0.0;
    if (!options_.recovery.enabled || !recovery_source_ || !observed) return 0.0;
    const double p = averages_.injection_probability(options_.recovery);
    if (!(p > 0.0) || !recovery_source_->prepare(context_)) return 0.0;
    const double eps = options_.recovery.kidnap_probability;
    injected_log_weight_ = std::log(eps) - std::log(p);
    kept_log_weight_ = std::log1p(-eps) - std::log1p(-p);
    return p;
  }

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
    const auto& moments =
        pose_moments_(engine_.particles(), engine_.weights(),
                      [](const robot::Pose& x) -> const robot::Pose& { return x; });
    summary_.mean = moments.mean;
    summary_.covariance = moments.covariance;
    summary_.particles = engine_.size();
    if (!summary_.updated) summary_.ess = effective_sample_size(engine_.weights());
  }

  Motion motion_;
  Motion step_motion_;  ///< motion_ for the current step length
  Observation observation_;
  Proposal proposal_;
  FilterOptions options_;
  Context context_;
  Prepared prepared_;
  [[no_unique_address]] GateKeptOf<Observation> gate_kept_;  ///< gate()'s kept parts
  ParticleEngine<robot::Pose> engine_;
  PoseMoments pose_moments_;
  std::vector<ParticleStats> stats_;
  std::vector<char> injected_;
  std::shared_ptr<RecoverySource<Context>> recovery_source_;
  LikelihoodAverages averages_;
  double injected_log_weight_ = 0.0, kept_log_weight_ = 0.0;
  std::uint64_t step_ = 0;
  StepSummary summary_;
};

}  // namespace implicit::filter
