#pragma once
// Proposals of the particle filter: how one particle moves from X^j_{n-1} to X^j_n and what its
// log weight gains. The engine (particle_filter.hpp) is the same for all of them.
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
// with a chi-square gate; bootstrap at the sampled pose with S = Sigma2, implicit at the prediction
// f^j with S = H Sigma1^j H^T + Sigma2. A detection outside the gate contributes the clutter
// density p0 = N(gate boundary; 0, Sigma2) when `clutter` is on, nothing otherwise.
//
// A user proposal is any type with `kPurpose` (its Rng purpose) and
//   double propose(const ProposalContext<Motion, Sensor>&, const Pose& previous, Rng&,
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

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/mcl_objective.hpp"
#include "implicit/filter/observation_proposals.hpp"
#include "implicit/robot/data_association.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

/// A detection with its landmark, if known (index into the map; -1 = associate).
struct LabelledMeasurement {
  Measurement z;
  int landmark = -1;
};

struct AssociationOptions {
  double gate = robot::kChiSquare2Dof99;  ///< chi-square gate on d^2 (2 dof, 99 %)
  bool clutter = true;                    ///< dropped detections contribute p0
  double min_range = 0.05;                ///< [m] landmarks closer than this are not candidates
};

/// Per-particle bookkeeping of one step (written by the proposal, reduced by the engine).
struct ParticleStats {
  int used = 0;           ///< detections associated (entered the likelihood)
  int dropped = 0;        ///< detections outside the gate
  int iterations = 0;     ///< Newton objective evaluations
  bool fallback = false;  ///< a Cholesky failed and a fallback (Gauss-Newton / prior) was used
  bool failed = false;    ///< the particle's weight was set to zero (non-finite model output)
};

/// Everything a proposal needs at one step; built by the engine, shared by all particles.
template <robot::MotionModel Motion, robot::LandmarkSensor Sensor>
struct ProposalContext {
  using SensorType = Sensor;
  const Motion* motion = nullptr;
  const Sensor* sensor = nullptr;
  std::span<const Landmark> map;
  Mat2 noise_information;      ///< Sigma2^-1 (computed once by a Cholesky solve)
  double log_det_noise = 0.0;  ///< log det Sigma2
  double log_clutter = 0.0;    ///< log p0
  AssociationOptions association;
  Control u;
  std::span<const LabelledMeasurement> z;  ///< empty: prediction only
};

namespace detail {

/// Prediction f, Cholesky of Sigma1 (and Sigma1 itself); false if Sigma1 is not SPD or f not
/// finite.
template <typename Motion>
bool predict(const Motion& motion, const Pose& previous, const Control& u, Pose& f, Mat3& sigma1,
             SmallFactor<3>& sigma1_factor) {
  if constexpr (robot::MotionModelWithCovariance<Motion>) {
    motion.predict_with_covariance(previous, u, f, sigma1);
  } else {
    f = motion.predict(previous, u);
    sigma1 = motion.process_covariance(previous, u);
  }
  return f.allFinite() && sigma1.allFinite() && sigma1_factor.compute(sigma1);
}

/// Maximum-likelihood association of z at pose x with innovation covariance
/// H pose_cov H^T + Sigma2 (pose_cov = nullptr: Sigma2 alone).
template <typename Ctx>
int associate(const Ctx& ctx, const Pose& x, const Mat3* pose_cov, const Measurement& z) {
  const Mat2& noise = ctx.sensor->noise_covariance();
  const double min_r2 = ctx.association.min_range * ctx.association.min_range;
  // Exact range pre-gate (see RangeFirstSensor): skips most landmarks without an atan2.
  const double range_bound =
      ctx.association.gate *
      (noise(0, 0) + (pose_cov ? (*pose_cov)(0, 0) + (*pose_cov)(1, 1) : 0.0));
  const double range_tol = std::sqrt(range_bound);
  return robot::associate_max_likelihood(
             static_cast<int>(ctx.map.size()),
             [&](int i, Measurement& e, Mat2& s) {
               const Landmark& m = ctx.map[static_cast<std::size_t>(i)];
               if ((m - x.template head<2>()).squaredNorm() < min_r2) return false;
               if constexpr (robot::RangeFirstSensor<typename Ctx::SensorType>) {
                 // |r - z_r| <= sqrt(bound), compared on squared distances (no square root).
                 const double d2 = (m - x.template head<2>()).squaredNorm();
                 const double lo = std::max(0.0, z(0) - range_tol), hi = z(0) + range_tol;
                 if (d2 < lo * lo || d2 > hi * hi) return false;
               }
               if (pose_cov) {
                 Measurement predicted;
                 Mat23 h;
                 if constexpr (robot::LandmarkSensorWithFusedJacobian<typename Ctx::SensorType>) {
                   ctx.sensor->predict_with_jacobian(x, m, predicted, h);
                 } else {
                   predicted = ctx.sensor->predict(x, m);
                   h = ctx.sensor->jacobian_pose(x, m);
                 }
                 e = ctx.sensor->residual(predicted, z);
                 const Eigen::Matrix<double, 2, 3> hp = h * (*pose_cov);
                 s.noalias() = hp * h.transpose();
                 s += noise;
               } else {
                 e = ctx.sensor->residual(ctx.sensor->predict(x, m), z);
                 s = noise;
               }
               return true;
             },
             ctx.association.gate)
      .index;
}

/// log p(z | x) of all detections of ctx at the pose x: maximum-likelihood association at x with
/// S = Sigma2 (labelled detections keep their landmark), a Gaussian term per associated detection
/// and log p0 per dropped one when clutter is on. The bootstrap's weight increment, and the target
/// density of global localization. Counts used and dropped detections in st.
template <typename Ctx>
double sensor_log_likelihood(const Ctx& ctx, const Pose& x, ParticleStats& st) {
  double log_w = 0.0;
  const double log_norm = -kLog2Pi - 0.5 * ctx.log_det_noise;  // log N(0; 0, Sigma2)
  for (const LabelledMeasurement& lz : ctx.z) {
    const int k = lz.landmark >= 0 ? lz.landmark : associate(ctx, x, nullptr, lz.z);
    if (k < 0) {
      ++st.dropped;
      if (ctx.association.clutter) log_w += ctx.log_clutter;
      continue;
    }
    ++st.used;
    const Measurement e =
        ctx.sensor->residual(ctx.sensor->predict(x, ctx.map[static_cast<std::size_t>(k)]), lz.z);
    log_w += log_norm - 0.5 * e.dot(ctx.noise_information * e);
  }
  return log_w;
}

}  // namespace detail

/// Standard MCL: sample the motion model, weight by the sensor likelihood.
struct BootstrapProposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  static constexpr bool kNeedsDerivatives = false;
  static constexpr std::string_view kName = "standard";

  template <typename Motion, typename Sensor>
  double propose(const ProposalContext<Motion, Sensor>& ctx, const Pose& previous, Rng& rng,
                 Pose& next, ParticleStats& st) const {
    Pose f;
    Mat3 sigma1_full;
    SmallFactor<3> sigma1;
    if (!detail::predict(*ctx.motion, previous, ctx.u, f, sigma1_full, sigma1)) {
      st.failed = true;
      next = previous;
      return -std::numeric_limits<double>::infinity();
    }
    const Vec<3> xi = rng.normal_vector<3>();  // one call: argument order is unspecified
    next = f + sigma1.matrixL() * xi;
    const double log_w = detail::sensor_log_likelihood(ctx, next, st);
    if (!std::isfinite(log_w) && log_w != -std::numeric_limits<double>::infinity()) {
      st.failed = true;
      return -std::numeric_limits<double>::infinity();
    }
    return log_w;
  }

  /// The same proposal for a filter on an observation model (observation_proposals.hpp).
  template <typename Motion, typename Observation>
  double propose(const ObservationContext<Motion, Observation>& ctx, const Pose& previous,
                 Rng& rng, Pose& next, ParticleStats& st) const {
    return detail::bootstrap_step(ctx, previous, rng, next, st);
  }
};

enum class ImplicitMap { kLinear, kRandom };

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

  /// The same proposal for a filter on an observation model (observation_proposals.hpp).
  template <typename Motion, typename Observation>
  double propose(const ObservationContext<Motion, Observation>& ctx, const Pose& previous,
                 Rng& rng, Pose& next, ParticleStats& st) const {
    return detail::implicit_step(ctx, map, scan_newton, starts, previous, rng, next, st);
  }

  template <typename Motion, typename Sensor>
  double propose(const ProposalContext<Motion, Sensor>& ctx, const Pose& previous, Rng& rng,
                 Pose& next, ParticleStats& st) const {
    constexpr double kNegInf = -std::numeric_limits<double>::infinity();
    Pose f;
    Mat3 sigma1_full;
    SmallFactor<3> sigma1;
    if (!detail::predict(*ctx.motion, previous, ctx.u, f, sigma1_full, sigma1)) {
      st.failed = true;
      next = previous;
      return kNegInf;
    }
    const Vec<3> xi = rng.normal_vector<3>();  // one call: argument order is unspecified
    if (ctx.z.empty()) {  // F is the Gaussian prior: mu = f, H = Sigma1^-1, all weights equal
      next = f + sigma1.matrixL() * xi;
      return 0.0;
    }
    // Sigma1^-1 is needed as a matrix (it is the prior's Hessian); Cholesky solves give it.
    const Mat3 prior_information = sigma1.inverse();
    const double constant = 1.5 * kLog2Pi + sigma1.log_det_L();  // 1/2 log det(2 pi Sigma1)
    MclObjective<Sensor> obj;
    obj.reset(*ctx.sensor, ctx.noise_information, f, prior_information, constant);
    const double per_term = kLog2Pi + 0.5 * ctx.log_det_noise;  // 1/2 log det(2 pi Sigma2)
    for (const LabelledMeasurement& lz : ctx.z) {
      const int k = lz.landmark >= 0 ? lz.landmark : detail::associate(ctx, f, &sigma1_full, lz.z);
      if (k < 0 || !obj.add(ctx.map[static_cast<std::size_t>(k)], lz.z)) {
        ++st.dropped;
        if (ctx.association.clutter) obj.add_constant(-ctx.log_clutter);
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
    // The kernel's maps and weight (spec §1.2, §1.3) with the factor used at mu.
    double log_w = kNegInf;
    if (map == ImplicitMap::kLinear) {
      log_w = linear_map(obj, nr.x, nr.factor, xi, next);
    } else if (implicit::random_map(obj, nr.x, nr.value, nr.factor, xi, next, log_w) !=
               RayStatus::kOk) {
      next = nr.x;  // weight zero: no root on the ray
    }
    if (!std::isfinite(log_w)) {
      st.failed = true;
      return kNegInf;
    }
    return log_w;
  }
};

}  // namespace implicit::filter
