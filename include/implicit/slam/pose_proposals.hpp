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
//   ImplicitPoseProposal  implicit sampling of F (PoseObjective) with the linear map: (A) point
//                         landmarks, S_i = Sigma2; (B) EKF landmarks, S_i = H_m P_i H_m^T + Sigma2
//                         frozen at f.
//
//   PoseStep step{sensor, f, sigma1, sigma1_llt, known};
//   PoseDraw d = FastSlam2Proposal{}.propose(step, rng);   // d.log_weight = -inf: weight zero
//
// A proposal's draws come from the stream of its kPurpose; it never throws or allocates per
// call (ImplicitPoseProposal keeps a per-thread buffer of landmark terms).

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/slam/proposals.hpp"

namespace implicit::slam {

/// What a pose proposal sees of one particle at one step.
struct PoseStep {
  const robot::RangeBearingSensor& sensor;
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

/// X ~ N(f, Sigma1): the move of every method at a step without a known landmark.
inline Pose draw_from_motion(const PoseStep& s, Rng& rng) {
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
  return -kLog2Pi - std::log(l(0, 0)) - std::log(l(1, 1)) - 0.5 * e.dot(llt.solve(e));
}
}  // namespace detail

struct FastSlam1Proposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  PoseDraw propose(const PoseStep& s, Rng& rng) const {
    PoseDraw d;
    d.x = draw_from_motion(s, rng);
    const Mat<2>& r = s.sensor.noise_covariance();
    for (const auto& k : s.known) {
      const Mat<2> hm = s.sensor.jacobian_landmark(d.x, k.mean);
      const Eigen::LLT<Mat<2>> llt(hm * k.cov * hm.transpose() + r);
      const Measurement nu =
          -robot::RangeBearingSensor::residual(s.sensor.predict(d.x, k.mean), k.z);
      d.log_weight += llt.info() == Eigen::Success ? detail::log_normal2(nu, llt)
                                                   : -std::numeric_limits<double>::infinity();
    }
    return d;
  }
};

struct FastSlam2Proposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  PoseDraw propose(const PoseStep& s, Rng& rng) const {
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

struct ImplicitPoseProposal {
  static constexpr std::uint64_t kPurpose = purpose::kReference;
  bool point_landmarks = false;  ///< (A): S_i = Sigma2; (B): the landmark covariance enters S_i
  NewtonOptions newton = pose_newton_options(20, 1e-10);

  PoseDraw propose(const PoseStep& s, Rng& rng) const {
    thread_local std::vector<LandmarkTerm> terms;
    PoseDraw d;
    d.x = s.f;
    terms.resize(s.known.size());
    bool ok = true;
    for (std::size_t i = 0; i < s.known.size(); ++i) {
      const auto& k = s.known[i];
      Mat<2> sk = s.sensor.noise_covariance();
      if (!point_landmarks) {
        const Mat<2> hm = s.sensor.jacobian_landmark(s.f, k.mean);
        sk += hm * k.cov * hm.transpose();
      }
      ok = ok && terms[i].set(k.mean, k.z, sk);
    }
    const PoseObjective F(s.f, s.sigma1, terms);
    PoseMinimum pm;
    if (ok && F.ok()) pm = newton_minimize<SmallFactor<3>>(F, s.f, newton);
    d.newton_solved = true;
    d.newton_iterations = pm.iterations;
    d.newton_converged = pm.converged();
    if (!pose_minimum_usable(pm)) return detail::failure(d);
    d.log_weight = linear_map(WithConstant{F}, pm.x, pm.factor, rng.normal_vector<3>(), d.x);
    return d;
  }
};

}  // namespace implicit::slam
