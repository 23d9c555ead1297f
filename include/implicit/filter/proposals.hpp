#pragma once
// Proposals of the particle filter: how one particle moves from X^j_{n-1} to X^j_n and what its
// log weight gains. The filter (monte_carlo_localization.hpp) is the same for all of them, and
// so is every proposal for all observation models: landmark detections
// (robot/landmark_observation.hpp), laser scans, a sensor of your own.
//
//   BootstrapProposal  standard MCL: X ~ N(f^j, Sigma1^j), weight *= p(z | X)         (spec §3.4)
//   ImplicitProposal   implicit MCL: minimise F^j, X = mu + L^-T xi (linear map) or the random
//                      map, weight *= (3/2) log 2pi - log det L + |xi|^2/2 - F^j(X)    (spec §3.4)
//
// In expectation over xi the implicit increment equals the predictive likelihood p(z_n |
// X^j_{n-1}), so the implicit filter is exact; the bootstrap increment has the same expectation
// over the motion noise but a much larger variance when the data are accurate and the model noisy.
//
// Association of unlabelled detections (spec §3.9): per particle, maximum likelihood over the map
// with a chi-square gate; bootstrap at the sampled pose with S = Sigma2 (the model's
// log_likelihood), implicit at the prediction f^j with S = H Sigma1^j H^T + Sigma2 (its own
// range-bearing path below, chosen at compile time for robot::LandmarkObservation). A detection
// outside the gate contributes the clutter density p0 = N(gate boundary; 0, Sigma2) when
// `clutter` is on, nothing otherwise.
//
// A user proposal is any type with `kPurpose` (its Rng purpose) and
//   double propose(const ObservationContext<Motion, Observation>&, const Pose& previous, Rng&,
//                  Pose& next, ParticleStats&) const;
// returning the log weight increment (-inf: weight zero). It must not allocate or throw.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"
#include "implicit/filter/mcl_objective.hpp"
#include "implicit/filter/observation_proposals.hpp"
#include "implicit/robot/landmark_observation.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

using robot::AssociationOptions;
using robot::LabelledMeasurement;

/// Per-particle bookkeeping of one step (written by the proposal, reduced by the engine).
struct ParticleStats {
  int used = 0;           ///< detections associated (entered the likelihood)
  int dropped = 0;        ///< detections outside the gate
  int iterations = 0;     ///< Newton objective evaluations
  bool fallback = false;  ///< a Cholesky failed and a fallback (Gauss-Newton / prior) was used
  bool failed = false;    ///< the particle's weight was set to zero (non-finite model output)
};

/// The implicit proposal's map (core/types.hpp).
using ImplicitMap = MapKind;

namespace detail {

/// The implicit proposal on landmark detections: the association once per particle at the
/// prediction f with S = H Sigma1 H^T + Sigma2, then F of that association (MclObjective, with
/// the range-bearing terms written out) minimised by Newton with the exact Hessian.
template <typename Motion, typename Sensor>
double landmark_implicit_step(
    const ObservationContext<Motion, robot::LandmarkObservation<Sensor>>& ctx, ImplicitMap map,
    const NewtonOptions& newton, const Pose& previous, Rng& rng, Pose& next, ParticleStats& st) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  Pose f;
  Mat3 sigma1_full;
  SmallFactor<3> sigma1;
  if (!predict_particle(ctx, previous, f, sigma1_full, sigma1, next, st)) return kNegInf;
  const Vec<3> xi = rng.normal_vector<3>();    // one call: argument order is unspecified
  if (ctx.z == nullptr || ctx.z->z.empty()) {  // F is the Gaussian prior: mu = f, all weights equal
    next = f + sigma1.matrixL() * xi;
    return 0.0;
  }
  const robot::LandmarkObservation<Sensor>& model = *ctx.observation;
  // Sigma1^-1 is needed as a matrix (it is the prior's Hessian); Cholesky solves give it.
  const Mat3 prior_information = sigma1.inverse();
  const double constant = gaussian_log_normaliser(3, sigma1.log_det_L());
  MclObjective<Sensor> obj;
  obj.reset(model.sensor(), model.noise_information(), f, prior_information, constant);
  const double per_term = gaussian_log_normaliser(2, 0.5 * model.log_det_noise());
  const std::span<const Landmark> landmarks = model.landmarks();
  for (const LabelledMeasurement& lz : ctx.z->z) {
    const int k = lz.landmark >= 0 ? lz.landmark : model.associate(f, &sigma1_full, lz.z);
    if (k < 0 || !obj.add(landmarks[static_cast<std::size_t>(k)], lz.z)) {
      ++st.dropped;
      if (model.association().clutter) obj.add_constant(-model.log_clutter());
      continue;
    }
    ++st.used;
    obj.add_constant(per_term);
  }
  const PoseMinimum nr = newton_minimize<SmallFactor<3>>(obj, f, newton);
  st.iterations += nr.evaluations;
  st.fallback = st.fallback || !nr.exact_factor;
  if (!usable(nr)) {
    // No usable Gaussian approximation (F not finite at the prediction): sample the prior and
    // weight by the likelihood, the bootstrap fallback, which is still a valid proposal.
    st.fallback = true;
    next = f + sigma1.matrixL() * xi;
    const double lw = -(obj.evaluate(next) - constant);
    if (!std::isfinite(lw)) {
      st.failed = true;
      return kNegInf;
    }
    // Prior density terms: F - constant - 1/2|xi|^2 is the negative log likelihood.
    return lw + 0.5 * xi.squaredNorm();
  }
  return sample_at_minimum(obj, nr, map, xi, next, st);
}

}  // namespace detail

/// Standard MCL: sample the motion model, weight by the sensor likelihood.
struct BootstrapProposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  static constexpr bool kNeedsDerivatives = false;
  static constexpr std::string_view kName = "standard";

  template <typename Motion, typename Observation>
  double propose(const ObservationContext<Motion, Observation>& ctx, const Pose& previous, Rng& rng,
                 Pose& next, ParticleStats& st) const {
    return detail::bootstrap_step(ctx, previous, rng, next, st);
  }
};

/// Implicit MCL: per particle, minimise F^j and sample with the linear (or random) map.
struct ImplicitProposal {
  static constexpr std::uint64_t kPurpose = purpose::kReference;
  static constexpr std::string_view kName = "implicit";
  static constexpr bool kNeedsDerivatives = true;

  ImplicitMap map = ImplicitMap::kLinear;
  NewtonOptions newton = mcl_newton_options();
  /// Newton's rules for observation models with a Gauss-Newton matrix (laser scans).
  NewtonOptions scan_newton = scan_newton_options();
  /// Observation models: Newton starts per particle, the prediction and starts - 1 draws from
  /// the prior; the lowest minimum centres the map (observation_proposals.hpp).
  int starts = 2;
  /// Observation models: Newton from each further start runs at most this many iterations and
  /// goes on only when it is already below the best minimum (observation_proposals.hpp,
  /// "Probing"); 0 = every start runs to convergence. Off by default: with poor odometry it
  /// loses more tracks (docs/performance.md, "Probing the further starts").
  int start_probe = 0;
  /// Observation models, linear map: the share of samples drawn from the motion prior instead
  /// (a defensive mixture with exact weights, observation_proposals.hpp); 0 = none.
  double defensive = 0.0;

  /// Landmark detections: the range-bearing path (detail::landmark_implicit_step) with
  /// `newton`; any other observation model: observation_proposals.hpp with `scan_newton`.
  template <typename Motion, typename Observation>
  double propose(const ObservationContext<Motion, Observation>& ctx, const Pose& previous, Rng& rng,
                 Pose& next, ParticleStats& st) const {
    if constexpr (robot::is_landmark_observation_v<Observation>)
      return detail::landmark_implicit_step(ctx, map, newton, previous, rng, next, st);
    else
      return detail::implicit_step(ctx, map, scan_newton, starts, start_probe, defensive, previous,
                                   rng, next, st);
  }
};

}  // namespace implicit::filter
