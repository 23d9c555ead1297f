#pragma once
// The sequential Monte Carlo engine: a weighted population of particles of any type, moved by a
// proposal, reweighted and resampled. Localization (particle_filter.hpp) and particle SLAM
// (slam/slam_filter.hpp) are both written on it; what a particle is, how it moves and what is
// read off the population (the collectors: means, maps) belong to them.
//
//   filter::ParticleEngine<MyState> engine(1000, x0);        // equal weights
//   engine.move([&](std::size_t j, MyState& x) {             // in parallel, one slot per call
//     Rng rng({seed, n, j, purpose::kProposal});             // keyed stream: thread-count free
//     return my_proposal(x, rng);                            // log weight increment (-inf: 0)
//   });
//   const auto r = engine.reweight();                        // log Z increment, ESS, all zero?
//   if (needs_resampling(r.ess, engine.size(), 0.5)) {
//     Rng rng({seed, n, 0, purpose::kResampling});
//     engine.resample(resample(ResamplingScheme::kSystematic, engine.weights(),
//                              engine.size(), rng));
//   }
//
// The layering follows model -> proposal -> engine -> collectors: the engine knows nothing of
// robots, maps or log formats. Its weights are kept normalised, in the log domain and as
// numbers; a step whose increments are all -inf leaves uniform weights and says so (a documented
// recovery: the caller reports it), a NaN increment is a bug of the proposal and throws.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::filter {

/// What one reweighting found.
struct Reweighting {
  /// log sum_j wbar^j exp(increment^j): the log marginal-likelihood increment of the step
  /// (-inf when every increment was -inf).
  double log_likelihood_increment = 0.0;
  double ess = 0.0;               ///< effective sample size of the new weights
  bool all_weights_zero = false;  ///< every increment was -inf: the weights were reset to uniform
};

template <typename Particle>
class ParticleEngine {
 public:
  ParticleEngine() = default;  ///< empty: assign() before anything else
  /// m copies of `initial` with equal weights.
  ParticleEngine(std::size_t m, const Particle& initial) { assign(m, initial); }

  std::size_t size() const { return particles_.size(); }
  std::span<const Particle> particles() const { return particles_; }
  std::span<Particle> particles() { return particles_; }
  std::span<const double> weights() const { return weights_; }          ///< normalised
  std::span<const double> log_weights() const { return log_weights_; }  ///< log of weights()
  /// The log weight increments of the last move(); a caller may add a factor (e.g. a position
  /// fix) before reweight().
  std::span<double> increments() { return increments_; }
  std::span<const double> increments() const { return increments_; }

  /// m copies of `p`, equal weights.
  void assign(std::size_t m, const Particle& p) {
    require(m >= 1, "particle engine: expected at least 1 particle, got {}", m);
    particles_.assign(m, p);
    resize_weights(m);
  }
  /// The given particles with equal weights; the population takes their number.
  void assign(std::span<const Particle> ps) {
    require(!ps.empty(), "particle engine: expected at least 1 particle, got none");
    particles_.assign(ps.begin(), ps.end());
    resize_weights(ps.size());
  }
  /// The given particles with log weights (any common offset; -inf allowed, not all).
  void assign(std::span<const Particle> ps, std::span<const double> log_weights) {
    require(!ps.empty() && ps.size() == log_weights.size(),
            "particle engine: expected as many log weights as particles (at least one), got {} "
            "and {}",
            log_weights.size(), ps.size());
    const double total = log_sum_exp(log_weights);
    require(std::isfinite(total),
            "particle engine: expected log weights with a finite total, got {}", total);
    particles_.assign(ps.begin(), ps.end());
    resize_weights(ps.size());
    for (std::size_t j = 0; j < ps.size(); ++j) {
      log_weights_[j] = log_weights[j] - total;
      weights_[j] = std::exp(log_weights_[j]);
    }
  }
  /// Draws every particle in parallel (particle j = draw(j), which must write nothing shared)
  /// and gives them equal weights.
  template <typename Draw>
  void generate(Draw&& draw, std::size_t grain = 16) {
    parallel_for(
        particles_.size(), [&](std::size_t j) { particles_[j] = draw(j); }, grain);
    reset_weights();
  }

  void reset_weights() {
    const double m = static_cast<double>(particles_.size());
    std::fill(log_weights_.begin(), log_weights_.end(), -std::log(m));
    std::fill(weights_.begin(), weights_.end(), 1.0 / m);
  }

  /// Moves every particle in parallel: `move(j, particle)` changes particle j in place and
  /// returns its log weight increment (-inf: weight zero). It may write only to slot j and must
  /// draw its randomness from a stream keyed by j; then the result does not depend on the
  /// number of threads. The weights are unchanged until reweight().
  template <typename Move>
  void move(Move&& move, std::size_t grain = 16) {
    resampled_ = false;
    parallel_for(
        particles_.size(), [&](std::size_t j) { increments_[j] = move(j, particles_[j]); }, grain);
  }

  /// Multiplies the weights by exp(increments) and normalises (log-sum-exp).
  Reweighting reweight() {
    const std::size_t m = particles_.size();
    Reweighting r;
    for (std::size_t j = 0; j < m; ++j) {
      require(
          !std::isnan(increments_[j]) && increments_[j] != std::numeric_limits<double>::infinity(),
          "particle engine: particle {} has log weight increment {} (expected a number or "
          "-inf)",
          j, increments_[j]);
      log_weights_[j] += increments_[j];
    }
    const double inc = log_sum_exp(log_weights_);  // the previous weights were normalised
    r.log_likelihood_increment = inc;
    if (!(inc > -std::numeric_limits<double>::infinity())) {
      r.all_weights_zero = true;
      reset_weights();
    } else {
      for (std::size_t j = 0; j < m; ++j) {
        log_weights_[j] -= inc;
        weights_[j] = std::exp(log_weights_[j]);
      }
    }
    r.ess = effective_sample_size(weights_);
    return r;
  }

  /// The new population is particle ancestors[k] for k = 0..n-1 (n may differ from size()),
  /// with equal weights. The old population and its weights stay readable as before_resampling()
  /// until the next move().
  void resample(std::span<const std::size_t> ancestors) {
    require(!ancestors.empty(), "particle engine: expected at least one ancestor, got none");
    previous_.resize(ancestors.size());
    for (std::size_t k = 0; k < ancestors.size(); ++k) {
      require(ancestors[k] < particles_.size(),
              "particle engine: ancestor {} is {}, expected an index below {}", k, ancestors[k],
              particles_.size());
      previous_[k] = particles_[ancestors[k]];
    }
    std::swap(particles_, previous_);
    previous_weights_.assign(weights_.begin(), weights_.end());
    resize_weights(particles_.size());
    resampled_ = true;
  }

  /// Frees the population and weights that resample() kept (before_resampling() is empty
  /// afterwards). For particles that share state copy on write, as grid SLAM's maps share tiles,
  /// the kept population holds a reference to every old tile: each write after resampling would
  /// copy its tile, even in a particle that is its ancestor's only descendant, and the old maps
  /// would stay in memory until the next resampling.
  void release_before_resampling() {
    previous_.clear();
    previous_weights_.clear();
  }

  /// Whether resample() ran since the last move().
  bool resampled() const { return resampled_; }
  /// The population and weights before the last resampling (valid while resampled()): estimates
  /// read from them are not blurred by the resampling noise.
  std::span<const Particle> before_resampling() const { return previous_; }
  std::span<const double> weights_before_resampling() const { return previous_weights_; }

 private:
  void resize_weights(std::size_t m) {
    log_weights_.resize(m);
    weights_.resize(m);
    increments_.assign(m, 0.0);
    reset_weights();
  }

  std::vector<Particle> particles_, previous_;
  std::vector<double> log_weights_, weights_, increments_, previous_weights_;
  bool resampled_ = false;
};

}  // namespace implicit::filter
