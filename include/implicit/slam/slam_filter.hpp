#pragma once
// Online landmark SLAM estimators behind one interface: EKF-SLAM, FastSLAM 1.0 and 2.0, and SLAM
// with implicit sampling in two variants (spec §3.5, paper §4.2).
//
//   slam::SlamOptions opt;
//   opt.method = slam::SlamMethod::kImplicitRb;
//   opt.particles = 100;
//   auto filter = slam::make_slam_filter(opt, data.initial_pose);
//   for (std::size_t n = 1; n <= data.steps(); ++n) {
//     filter->set_step_length(data.step_length(n));   // the data's own time stamps
//     filter->step(n, data.control(n), data.observations(n));
//     slam::PoseEstimate est = filter->pose();
//   }
//
// Methods (the CLI names in brackets):
//   kEkf [ekf]              joint Gaussian over pose and map; Joseph-form updates; O(N^2) per step.
//   kFastSlam1 [fastslam1]  pose from the motion model, EKF landmarks, weight = innovation density.
//   kFastSlam2 [fastslam2]  pose from the linearised optimal proposal N(mu_x, Sigma_x), weight
//                           includes the pose term (H_x Sigma1 H_x^T in the innovation covariance).
//   kImplicit [implicit]    the paper's implicit SLAM (A): point landmarks fixed at creation; a new
//                           landmark is sampled jointly with the pose by the 5-D linear map, a
//                           known one makes the step implicit MCL with the particle's landmark.
//   kImplicitRb [implicit-rb] (B), Rao-Blackwellised: implicit pose proposal against EKF
//                           landmarks (innovation covariance frozen at the prediction), then an
//                           EKF update of the landmark.
//
// The particle methods differ only in their pose proposal, a plug-in: make_particle_slam_filter
// (below) runs any type modelling LandmarkPoseProposal (pose_proposals.hpp), e.g. a user's, and
// make_slam_filter picks the built-in one of options.method (pose_proposal).
//
// Association: kKnown uses Observation::landmark (tests, synthetic data); kMaximumLikelihood picks,
// per particle (EKF: once), the landmark with the smallest d^2 + log det S among those inside the
// chi-square gate and creates a new landmark when none is inside. A new landmark contributes the
// constant density new_landmark_density (p0, in measurement units 1/(m rad)) to the weight.
//
// Mistakes to avoid: comparing weights of particles that created different numbers of landmarks
// without p0 (they would be incomparable), and reading Sigma2 as standard deviations (spec E27).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/ute_model.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/pose_proposals.hpp"

namespace implicit::slam {

enum class SlamMethod { kEkf, kFastSlam1, kFastSlam2, kImplicit, kImplicitRb };
enum class Association { kKnown, kMaximumLikelihood };

std::string_view to_string(SlamMethod m);
/// "ekf" | "fastslam1" | "fastslam2" | "implicit" | "implicit-rb"; throws InvalidArgument
/// otherwise.
SlamMethod parse_slam_method(std::string_view name);
std::string_view to_string(Association a);
/// "known" | "ml"; throws InvalidArgument otherwise.
Association parse_association(std::string_view name);

struct SlamOptions {
  SlamMethod method = SlamMethod::kImplicitRb;
  Association association = Association::kKnown;
  int particles = 100;      ///< M (ignored by EKF-SLAM)
  std::uint64_t seed = 1;   ///< filter randomness: Rng({seed, step, particle, purpose})
  robot::UteParams motion;  ///< the Ute's parameters (Sigma1 from P, Q), unless `model`
  /// The filter's motion model when it is not the Ute (any LinearizableMotionModel, e.g.
  /// robot::UnicycleModel or your own); empty: robot::UteModel(motion).
  std::optional<robot::AnyMotionModel> model;
  robot::RangeBearingSensor sensor;                  ///< Sigma2
  double gate_chi2 = 9.21;                           ///< chi^2_2 99 % gate of the ML association
  double new_landmark_density = 1.0 / (15.0 * kPi);  ///< p0 [1/(m rad)], spec §3.10
  double resample_threshold = 0.5;  ///< resample (systematic) when ESS < threshold * M
  double min_range = 0.0;  ///< detections closer than this are ignored (counted as skipped)
  /// ML association through the spatial grid index (slam/landmark_index.hpp); false: linear
  /// scan. Both give the same association; only the cost differs.
  bool association_index = true;
  int newton_max_iterations = 20;
  double newton_decrement_tolerance = 1e-10;  ///< stop when g^T H^-1 g < this

  /// Throws InvalidArgument naming the offending field.
  void validate() const;
};

struct PoseEstimate {
  Pose mean = Pose::Zero();     ///< weighted mean (heading: circular mean)
  Mat<3> cov = Mat<3>::Zero();  ///< weighted covariance (heading deviations wrapped)
};

struct MapEstimate {
  std::vector<Landmark> landmarks;  ///< estimated positions
  std::vector<int> ids;             ///< true landmark id (known association) or -1
};

struct SlamStats {
  std::size_t steps = 0;
  std::size_t updates = 0;        ///< detections used to update a known landmark
  std::size_t new_landmarks = 0;  ///< detections that created a landmark (per filter or best)
  std::size_t skipped = 0;        ///< detections ignored (below min_range)
  std::size_t resamplings = 0;
  std::size_t weighted_steps = 0;     ///< steps with a detection (ESS averaged over these)
  double ess_fraction_sum = 0.0;      ///< sum over weighted steps of ESS/M
  std::size_t newton_iterations = 0;  ///< total, over particles and updates
  std::size_t newton_solves = 0;
  std::size_t newton_not_converged = 0;
  std::size_t degenerate_steps = 0;  ///< all weights zero: uniform weights were used
  double mean_ess_fraction() const {
    return weighted_steps > 0 ? ess_fraction_sum / static_cast<double>(weighted_steps) : 1.0;
  }
};

class SlamFilter {
 public:
  virtual ~SlamFilter() = default;
  /// Step n (>= 1): move with u, then process the detections of step n.
  virtual void step(std::uint64_t n, const Control& u, std::span<const Observation> obs) = 0;
  /// Starts with a known map (landmark ids = indices; covariance zero): for tests that reduce
  /// SLAM to localisation. Must be called before the first step.
  /// The length [s] of the following steps (the data's own time stamps); until called, the
  /// motion model's dt().
  virtual void set_step_length(double dt) = 0;
  virtual void set_known_map(std::span<const Landmark> landmarks) = 0;
  virtual PoseEstimate pose() const = 0;
  virtual MapEstimate map() const = 0;
  virtual const SlamStats& stats() const = 0;
  /// Bytes of landmark storage held by the filter (shared nodes counted once).
  virtual std::size_t map_bytes() const = 0;
};

/// Builds the estimator chosen in options.method, starting at the known pose x0.
std::unique_ptr<SlamFilter> make_slam_filter(const SlamOptions& options, const Pose& x0);

/// Particle SLAM with any pose proposal (a type modelling LandmarkPoseProposal, e.g. a user's,
/// converts to AnyPoseProposal), starting at x0. Everything but the proposal comes from options:
/// association, particles, seed, motion model, sensor, gate, p0, resampling; options.method and
/// the newton_* fields are not read (the proposal carries its own).
///
///   struct MyProposal {
///     static constexpr std::uint64_t kPurpose = purpose::kProposal;
///     PoseDraw propose(const PoseStep<>& step, Rng& rng) const;
///   };
///   auto filter = slam::make_particle_slam_filter(options, x0, MyProposal{});
std::unique_ptr<SlamFilter> make_particle_slam_filter(const SlamOptions& options, const Pose& x0,
                                                      AnyPoseProposal proposal);

/// The built-in proposal of options.method (fastslam1, fastslam2, implicit, implicit-rb, with
/// options' Newton settings): make_slam_filter(options, x0) is make_particle_slam_filter(options,
/// x0, pose_proposal(options)) for those. Throws InvalidArgument for kEkf.
AnyPoseProposal pose_proposal(const SlamOptions& options);

}  // namespace implicit::slam
