#pragma once
// The pose proposals of particle SLAM: how one particle's pose moves at a step where it sees
// known landmarks, and what its log weight gains (spec §3.5). The SLAM filter (slam_filter.hpp)
// runs them as plug-ins on the generic engine (filter/particle_engine.hpp); association, new
// landmarks and the EKF updates of the map after the move are the same for all of them.
//
//   FastSlam1Proposal     X ~ N(f, Sigma1); weight *= prod_i N(nu_i; 0, H_m P_i H_m^T + Sigma2)
//                         at the sampled X (Montemerlo et al. 2002).
//   FastSlam2Proposal     the measurement model linearised at f (linearized_optimal_proposal);
//                         the weight includes the pose term H_x Sigma1 H_x^T.
//   ImplicitPoseProposal  implicit sampling of F (set_pose_objective) with the linear map:
//                         (A) point landmarks, S_i = Sigma2; (B) EKF landmarks,
//                         S_i = H_m P_i H_m^T + Sigma2 frozen at f.
//
// A proposal is any type modelling LandmarkPoseProposal (below): the three above, or a user's,
// which plugs into make_particle_slam_filter (slam_filter.hpp) without editing the library. It
// reads the sensor through the observation seam's concept (robot::LandmarkSensor), so a proposal
// written against PoseStep<Sensor> serves any landmark sensor.
//
//   PoseStep<> step{sensor, f, sigma1, sigma1_llt, known};
//   PoseDraw d = FastSlam2Proposal{}.propose(step, rng);   // d.log_weight = -inf: weight zero
//
// A proposal's draws come from the stream of its kPurpose; it never throws or allocates per
// call.

#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/slam/proposals.hpp"

namespace implicit::slam {

/// What a pose proposal sees of one particle at one step (all of it valid during the call only).
template <robot::LandmarkSensor Sensor = robot::RangeBearingSensor>
struct PoseStep {
  const Sensor& sensor;                  ///< h(x, m), its Jacobians and Sigma2
  const Pose& f;                         ///< the motion model's prediction
  const Mat<3>& sigma1;                  ///< process covariance at the previous pose
  const Eigen::LLT<Mat<3>>& sigma1_llt;  ///< its Cholesky factor (succeeded)
  std::span<const KnownLandmark> known;  ///< detections of landmarks already in the map
};

/// A proposed pose and its log weight increment (-inf: weight zero).
struct PoseDraw {
  Pose x = Pose::Zero();
  double log_weight = 0.0;
  bool failed = false;         ///< no pose could be proposed: weight zero, x = f, map unchanged
  bool newton_solved = false;  ///< implicit proposals: a pose solve ran
  bool newton_converged = false;
  int newton_iterations = 0;
};

/// A pose drawn jointly with the landmark of a step's only detection, which is new (implicit
/// SLAM (A)). log_weight is against the target N(x; f, Sigma1) N(z; h(x, m), Sigma2) with a flat
/// prior on m in the plane; the filter multiplies by p0 / z_range, which makes that prior the
/// new-landmark density p0 in measurement units (spec §3.10).
struct NewLandmarkDraw {
  Pose x = Pose::Zero();
  Landmark m = Landmark::Zero();
  double log_weight = 0.0;
  bool failed = false;  ///< weight zero: the filter places the landmark from x = f instead
};

/// A pose proposal of particle landmark SLAM, the filter's plug-in (make_particle_slam_filter):
///   P::kPurpose                 the Rng purpose (core/rng.hpp) of its draws; the filter gives
///                               it Rng({seed, step, particle, kPurpose}).
///   p.propose(step, rng)        -> PoseDraw: the particle's new pose and log weight increment,
///                               called only at a step where the particle sees at least one
///                               known landmark (step.known); at other steps the filter draws
///                               X ~ N(f, Sigma1) from the same stream (draw_from_motion). It is
///                               called in parallel, one particle per call: const, no throw, no
///                               allocation per call.
/// Optional members (detected, defaults in brackets):
///   p.point_landmarks()         -> bool [false]: landmarks are points fixed at creation (zero
///                               covariance, no EKF update); false: EKF landmarks.
///   p.propose_with_new_landmark(step, z, rng) -> std::optional<NewLandmarkDraw> [none]: at a
///                               step whose only detection z is of a new landmark, the pose and
///                               that landmark jointly; std::nullopt: the usual path.
/// The filter, not the proposal, does association, new landmarks and the EKF updates.
template <typename P, typename Sensor = robot::RangeBearingSensor>
concept LandmarkPoseProposal = std::copy_constructible<P> &&
    requires(const P& p, const PoseStep<Sensor>& s, Rng& rng) {
  { P::kPurpose } -> std::convertible_to<std::uint64_t>;
  { p.propose(s, rng) } -> std::same_as<PoseDraw>;
};

/// The optional members of LandmarkPoseProposal.
template <typename P>
concept PointLandmarkProposal = requires(const P& p) {
  { p.point_landmarks() } -> std::convertible_to<bool>;
};
template <typename P, typename Sensor = robot::RangeBearingSensor>
concept JointNewLandmarkProposal = requires(const P& p, const PoseStep<Sensor>& s,
                                            const Measurement& z, Rng& rng) {
  { p.propose_with_new_landmark(s, z, rng) } -> std::same_as<std::optional<NewLandmarkDraw>>;
};
/// The most known landmarks one step of the proposal takes (a fixed-capacity objective). The
/// filter refuses a step that gives a particle more, naming the step, rather than weighting the
/// particle zero in silence; a proposal without this member takes any number.
template <typename P>
concept BoundedProposal = requires(const P& p) {
  { p.max_known_landmarks() } -> std::convertible_to<std::size_t>;
};

/// X ~ N(f, Sigma1): the move of every method at a step without a known landmark.
template <typename Sensor>
Pose draw_from_motion(const PoseStep<Sensor>& s, Rng& rng) {
  return s.f + s.sigma1_llt.matrixL() * rng.normal_vector<3>();
}

namespace detail {
inline PoseDraw failure(PoseDraw d) {
  d.failed = true;
  d.log_weight = -std::numeric_limits<double>::infinity();
  return d;
}
inline double log_normal2(const Vec<2>& e, const Eigen::LLT<Mat<2>>& llt) {
  const Mat<2> l = llt.matrixL();
  return -gaussian_log_normaliser(2, std::log(l(0, 0))) - std::log(l(1, 1)) -
         0.5 * e.dot(llt.solve(e));
}
}  // namespace detail

struct FastSlam1Proposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  template <typename Sensor>
  PoseDraw propose(const PoseStep<Sensor>& s, Rng& rng) const {
    PoseDraw d;
    d.x = draw_from_motion(s, rng);
    const Mat<2>& r = s.sensor.noise_covariance();
    for (const auto& k : s.known) {
      const Mat<2> hm = landmark_jacobian(s.sensor, d.x, k.mean);
      const Eigen::LLT<Mat<2>> llt(hm * k.cov * hm.transpose() + r);
      const Measurement nu = -s.sensor.residual(s.sensor.predict(d.x, k.mean), k.z);
      d.log_weight += llt.info() == Eigen::Success ? detail::log_normal2(nu, llt)
                                                   : -std::numeric_limits<double>::infinity();
    }
    return d;
  }
};

struct FastSlam2Proposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  template <typename Sensor>
  PoseDraw propose(const PoseStep<Sensor>& s, Rng& rng) const {
    PoseDraw d;
    d.x = s.f;
    const LinearizedProposal lp = linearized_optimal_proposal(s.sensor, s.f, s.sigma1_llt, s.known);
    if (!lp.ok) return detail::failure(d);
    const Vec<3> xi = rng.normal_vector<3>();
    d.x = lp.mean + lp.L.transpose().triangularView<Eigen::Upper>().solve(xi);
    d.log_weight = lp.log_weight;
    return d;
  }
};

/// Implicit SLAM, (A) with point_landmarks (the paper's) or (B) without: the filter layer's pose
/// objective (set_pose_objective) for any landmark sensor; (A)'s joint draw of a new landmark is
/// written out for the range-bearing sensor (NewLandmarkObjective).
struct ImplicitPoseProposal {
  static constexpr std::uint64_t kPurpose = purpose::kReference;
  bool point = false;  ///< (A): S_i = Sigma2, landmarks fixed; (B): S_i = H_m P_i H_m^T + Sigma2
  NewtonOptions newton = pose_newton_options(20, 1e-10);

  bool point_landmarks() const { return point; }
  std::size_t max_known_landmarks() const { return kMaxKnownPerStep; }

  template <typename Sensor>
  PoseDraw propose(const PoseStep<Sensor>& s, Rng& rng) const {
    PoseObjective<Sensor> F;
    PoseDraw d;
    d.x = s.f;
    filter::PoseMinimum pm;
    if (set_pose_objective(F, s.sensor, s.f, s.sigma1_llt, s.known, point))
      pm = newton_minimize<SmallFactor<3>>(F, s.f, newton);
    d.newton_solved = true;
    d.newton_iterations = pm.iterations;
    d.newton_converged = pm.converged();
    if (!filter::usable(pm)) return detail::failure(d);
    d.log_weight = linear_map(F, pm.x, pm.factor, rng.normal_vector<3>(), d.x);
    return d;
  }

  /// (A): the pose and the new landmark jointly, by the 5-D linear map around the closed-form
  /// minimiser of NewLandmarkObjective. (B): std::nullopt (the landmark is placed by inversion).
  std::optional<NewLandmarkDraw> propose_with_new_landmark(
      const PoseStep<robot::RangeBearingSensor>& s, const Measurement& z, Rng& rng) const {
    if (!point) return std::nullopt;
    NewLandmarkDraw d;
    d.x = s.f;
    const NewLandmarkObjective F(s.f, s.sigma1, z, s.sensor.noise_covariance());
    SmallFactor<5> factor;
    if (!F.ok() || !factor.compute(F.hessian_at_minimizer())) {
      d.failed = true;
      return d;
    }
    Vec<5> sample;
    d.log_weight =
        linear_map(WithConstant{F}, F.minimizer(), factor, rng.normal_vector<5>(), sample);
    d.x = sample.head<3>();
    d.m = sample.tail<2>();
    return d;
  }
};

static_assert(LandmarkPoseProposal<FastSlam1Proposal>);
static_assert(LandmarkPoseProposal<FastSlam2Proposal>);
static_assert(LandmarkPoseProposal<ImplicitPoseProposal>);
static_assert(PointLandmarkProposal<ImplicitPoseProposal>);
static_assert(JointNewLandmarkProposal<ImplicitPoseProposal>);
static_assert(LandmarkPoseProposal<FastSlam1Proposal, robot::MountedRangeBearingSensor>);
static_assert(LandmarkPoseProposal<FastSlam2Proposal, robot::MountedRangeBearingSensor>);
static_assert(LandmarkPoseProposal<ImplicitPoseProposal, robot::MountedRangeBearingSensor>);

/// Any LandmarkPoseProposal for the filter's sensor, behind one type: what the particle SLAM
/// filter holds. One indirect call per particle and step (the proposal itself is not copied per
/// call; copies of an AnyPoseProposal share it).
class AnyPoseProposal {
 public:
  using Step = PoseStep<robot::RangeBearingSensor>;

  // The self-exclusion comes first so that copying an AnyPoseProposal never asks whether
  // AnyPoseProposal itself models the concept (which would recurse through this constructor).
  template <class P>
  requires(!std::same_as<std::remove_cvref_t<P>, AnyPoseProposal> && LandmarkPoseProposal<P>)
      AnyPoseProposal(P proposal)  // NOLINT(google-explicit-constructor): any proposal converts
      : self_(std::make_shared<const P>(std::move(proposal))),
        purpose_(P::kPurpose),
        propose_([](const void* self, const Step& s, Rng& rng) {
          return static_cast<const P*>(self)->propose(s, rng);
        }) {
    if constexpr (PointLandmarkProposal<P>)
      point_landmarks_ = static_cast<const P*>(self_.get())->point_landmarks();
    if constexpr (BoundedProposal<P>)
      max_known_ = static_cast<const P*>(self_.get())->max_known_landmarks();
    if constexpr (JointNewLandmarkProposal<P>)
      joint_ = [](const void* self, const Step& s, const Measurement& z, Rng& rng) {
        return static_cast<const P*>(self)->propose_with_new_landmark(s, z, rng);
      };
  }

  std::uint64_t purpose() const { return purpose_; }
  bool point_landmarks() const { return point_landmarks_; }
  std::size_t max_known_landmarks() const { return max_known_; }
  PoseDraw propose(const Step& s, Rng& rng) const { return propose_(self_.get(), s, rng); }
  std::optional<NewLandmarkDraw> propose_with_new_landmark(const Step& s, const Measurement& z,
                                                           Rng& rng) const {
    if (joint_ == nullptr) return std::nullopt;
    return joint_(self_.get(), s, z, rng);
  }

 private:
  std::shared_ptr<const void> self_;
  std::uint64_t purpose_ = 0;
  bool point_landmarks_ = false;
  std::size_t max_known_ = std::numeric_limits<std::size_t>::max();
  PoseDraw (*propose_)(const void*, const Step&, Rng&) = nullptr;
  std::optional<NewLandmarkDraw> (*joint_)(const void*, const Step&, const Measurement&,
                                           Rng&) = nullptr;
};

}  // namespace implicit::slam
