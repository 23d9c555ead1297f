#pragma once
// What Monte Carlo localization (monte_carlo_localization.hpp) is configured with and reports per
// step, whatever its observation model: FilterOptions, StepSummary, and the PositionFix a step may
// also weight by.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "implicit/core/error.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/filter/kld.hpp"
#include "implicit/filter/recovery.hpp"
#include "implicit/robot/landmark_observation.hpp"

namespace implicit::filter {

struct FilterOptions {
  std::size_t particles = 100;
  double resample_threshold = 0.5;  ///< resample when ESS < threshold * M
  ResamplingScheme resampling = ResamplingScheme::kSystematic;
  std::uint64_t seed = 0;  ///< first field of every stream key
  /// Landmark detections only (robot::LandmarkObservation): the gate, clutter and minimum range.
  robot::AssociationOptions association;
  /// Adaptive particle count: at every update step resample to the KLD bound (kld.hpp). The
  /// first count is `particles`.
  KldOptions kld;
  /// Injection of particles from a recovery source when the filter looks lost (recovery.hpp);
  /// needs set_recovery_source().
  RecoveryOptions recovery;
};

struct StepSummary {
  std::size_t step = 0;  ///< 1-based step counter
  robot::Pose mean = robot::Pose::Zero();
  robot::Mat3 covariance = robot::Mat3::Zero();
  double ess = 0.0;  ///< at update steps: after weighting, before any resampling
  bool resampled = false;
  bool updated = false;                   ///< an observation (or a fix) was processed at this step
  double log_likelihood_increment = 0.0;  ///< 0 at prediction-only steps
  bool all_weights_zero = false;          ///< every particle got weight 0: weights reset to uniform
  /// Counting models (landmark detections): mean over particles, weighted by the previous weights;
  /// other models: the parts of the prepared observation (beams).
  double detections_used = 0.0;
  double detections_dropped = 0.0;  ///< counting models: idem
  double newton_evaluations = 0.0;  ///< mean over particles
  int fallbacks = 0;                ///< particles that needed a Cholesky fallback
  int failures = 0;                 ///< particles with a non-finite model output (weight 0)
  /// Parts of the observation the prediction gate left out (labelled detections that the
  /// predicted pose distribution could not produce: robot/landmark_observation.hpp, gate()).
  int gated = 0;
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

inline void validate(const PositionFix& fix) {
  require(fix.position.allFinite() && fix.std > 0 && std::isfinite(fix.std),
          "particle filter: expected a finite position fix with a positive std, got ({}, {}) "
          "std {}",
          fix.position(0), fix.position(1), fix.std);
}

}  // namespace implicit::filter
