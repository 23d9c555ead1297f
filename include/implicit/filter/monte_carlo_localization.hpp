#pragma once
// Monte Carlo localization on any observation model (robot/observation_model.hpp): a laser scan
// against an occupancy grid (robot/likelihood_field.hpp), or a sensor of your own. The engine
// (particle_engine.hpp), the proposals (proposals.hpp: bootstrap and implicit), KLD-sampling
// (kld.hpp) and recovery (recovery.hpp) are the ones of the landmark filter (particle_filter.hpp).
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
// update under KLD-sampling). FilterOptions::association is not used here (it is the landmark
// sensor's).
//
// The implicit proposal needs the model's derivatives: a model that is not differentiable (e.g.
// the likelihood field with nav2's cubed-sum aggregation) is refused at construction, with the
// model's reason.

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
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/kld.hpp"
#include "implicit/filter/particle_engine.hpp"
#include "implicit/filter/particle_filter.hpp"
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

template <robot::PoseMotionModel Motion, robot::ObservationModel Observation, typename Proposal>
class MonteCarloLocalization {
 public:
  using Control = robot::ControlOf<Motion>;
  using Prepared = typename Observation::Prepared;
  using Context = ObservationContext<Motion, Observation>;

  MonteCarloLocalization(Motion motion, Observation observation, Proposal proposal,
                         FilterOptions options)
      : motion_(std::move(motion)),
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

  /// Starts from weighted particles (log weights, any common offset), e.g. a global start; the
  /// particle count becomes particles.size().
  void initialize(std::span<const robot::Pose> particles, std::span<const double> log_weights) {
    engine_.assign(particles, log_weights);
    resize_scratch(particles.size());
    restart();
  }

  /// The observation prepared as the model would at a step (for global starts and tools).
  Prepared prepare(const typename Observation::Observation& z, std::string_view where) const {
    return observation_.prepare(z, where);
  }

  /// One motion step with control u, no observation: the weights are unchanged.
  const StepSummary& step(const Control& u) { return step_impl(u, nullptr, 0); }

  /// One motion step with control u and the observation seen after it; `where` names it in
  /// errors (e.g. the file and line).
  const StepSummary& step(const Control& u, const typename Observation::Observation& z,
                          std::string_view where = "observation") {
    prepared_ = observation_.prepare(z, where);
    return step_impl(u, &prepared_, observation_size(prepared_));
  }

  /// A step with an observation prepared by prepare().
  const StepSummary& step_prepared(const Control& u, const Prepared& z) {
    return step_impl(u, &z, observation_size(z));
  }

 private:
  static int observation_size(const Prepared& z) {
    if constexpr (requires { z.size(); })
      return static_cast<int>(z.size());
    else
      return 1;
  }

  void restart() {
    step_ = 0;
    averages_.reset();
    summary_ = StepSummary{};
    summarize();
  }

  const StepSummary& step_impl(const Control& u, const Prepared* z, int terms) {
    ++step_;
    context_.motion = &motion_;
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
        Rng choice({options_.seed, n, j, purpose::kRecovery});
        if (choice.uniform() < p) {
          injected_[j] = 1;
          return injected_log_weight_ + recovery_source_->draw(context_, choice, x);
        }
      }
      Rng rng({options_.seed, n, j, Proposal::kPurpose});
      return proposal_.propose(context_, previous, rng, x, stats_[j]) + kept_log_weight_;
    });
    summary_ = StepSummary{};
    summary_.step = step_;
    summary_.updated = z != nullptr;
    for (const ParticleStats& s : stats_) {
      summary_.newton_evaluations += s.iterations;
      summary_.fallbacks += s.fallback ? 1 : 0;
      summary_.failures += s.failed ? 1 : 0;
    }
    summary_.newton_evaluations /= static_cast<double>(stats_.size());
    summary_.detections_used = terms;
    summary_.injection_probability = p;
    for (char c : injected_) summary_.injected += c;
    if (summary_.updated || summary_.failures > 0) update_weights();
    if (options_.recovery.enabled && z != nullptr) {
      if (p == 0.0) summary_.log_likelihood_increment += std::log1p(-options_.recovery.kidnap_probability);
      averages_.update(summary_.log_likelihood_increment, std::max(terms, 1), options_.recovery);
    }
    summarize();
    return summary_;
  }

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
    summary_.ess = r.ess;
    const std::size_t m = engine_.size();
    if (options_.kld.enabled) {
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
                                        [](const robot::Pose& x) -> const robot::Pose& { return x; });
    summary_.mean = moments.mean;
    summary_.covariance = moments.covariance;
    summary_.particles = engine_.size();
    if (!summary_.updated) summary_.ess = effective_sample_size(engine_.weights());
  }

  Motion motion_;
  Observation observation_;
  Proposal proposal_;
  FilterOptions options_;
  Context context_;
  Prepared prepared_;
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
