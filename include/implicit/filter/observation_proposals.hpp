#pragma once
// The two proposals for any observation model (robot/observation_model.hpp): what
// BootstrapProposal and ImplicitProposal (proposals.hpp) do at a step of the filter
// (monte_carlo_localization.hpp). Landmark detections take the bootstrap below and an implicit
// path of their own (proposals.hpp: association at the prediction, range-bearing objective).
//
//   bootstrap: X ~ N(f, Sigma1), log w += log p(z | X)
//   implicit:  minimise F = prior + observation terms (pose_objective.hpp), X = mu + L^-T xi
//              (linear map) or the random map, log w += (3/2) log 2pi - log det L + |xi|^2/2 - F(X)
//
// Both use the same Gaussian transition, so they target the same posterior; the implicit
// increment's expectation over xi is the predictive likelihood p(z | X_{n-1}).
//
// Several starts. A scan's -log p(z | x) has local minima (a corridor seen from the wrong
// place, a wall one cell off), and the minimum nearest the prediction f need not be the one
// that matters when the odometry is poor. With `starts` > 1 the implicit proposal also runs
// Newton from starts - 1 poses drawn from the prior N(f, Sigma1) and centres the map at the
// lowest minimum found. The weights stay exact: the starts s are drawn first, x ~ q(x | s) =
// N(mu(s), H(s)^-1), and w = p(x | x') p(z | x) / q(x | s) has expectation
// E_s[ integral p(x | x') p(z | x) dx ] = p(z | x') for every function mu(s), H(s) (importance
// sampling on the space (s, x) with the target p(x | x', z) q(s)).
//
// Probing the further starts. Most draws from the prior fall in the basin of the minimum already
// found, and running Newton to convergence there again doubles the cost of a particle. With
// `probe` = P > 0 Newton from a further start runs at most P iterations; it is continued to
// convergence only when its value is then below the lowest minimum found so far (a start that
// has not got below that value by then rarely ends lower). The centre is still a function of the
// starts and the objective, so the weights stay exact; a start cut short only means that a lower
// minimum may be missed, which costs effective sample size, not correctness. On ACES (M = 50,
// docs/performance.md) P = 3 took 15.4 evaluations of F per particle instead of 22.6, at the same
// RMSE and ESS; but with poor odometry (the bag fixture, alphas 0.12) it lost 9 runs of 300 where
// P = 0 lost 3 (a start that needed more than P iterations to get below was dropped), so the
// default, P = 0, runs every start through.
//
// A defensive share. When every start lands in the wrong minimum (the prediction is poor and
// the scan fits a wrong place better), every implicit sample sits there and no particle is
// left where the robot is. With `defensive` = a > 0 (linear map) the sample comes from the
// motion prior with probability a, else from the implicit Gaussian, and the weight divides by the
// mixture's density: q(x) = a N(x; f, Sigma1) + (1 - a) N(x; mu, H^-1), w = exp(-F(x)) / q(x),
// exact for any a (defensive importance sampling, Hesterberg 1995). It costs one more uniform
// draw and two 3x3 triangular solves per particle.

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/pose_objective.hpp"
#include "implicit/robot/observation_model.hpp"

namespace implicit::filter {

/// Everything a proposal needs at one step of a filter on an observation model.
template <typename Motion, typename Observation>
struct ObservationContext {
  const Motion* motion = nullptr;
  const Observation* observation = nullptr;
  robot::ControlOf<Motion> u{};
  const typename Observation::Prepared* z = nullptr;  ///< null: prediction only
};

namespace detail {

/// The prediction f, Sigma1 and its Cholesky factor; false if Sigma1 is not SPD or f not finite.
template <robot::PoseMotionModel Motion>
bool predict_pose(const Motion& motion, const robot::Pose& previous,
                  const robot::ControlOf<Motion>& u, robot::Pose& f, robot::Mat3& sigma1,
                  SmallFactor<3>& factor) {
  if constexpr (robot::PoseMotionModelWithCovariance<Motion>) {
    motion.predict_with_covariance(previous, u, f, sigma1);
  } else {
    f = motion.predict(previous, u);
    sigma1 = motion.process_covariance(previous, u);
  }
  return f.allFinite() && sigma1.allFinite() && factor.compute(sigma1);
}

/// The particle's prediction f, Sigma1 and its factor at the step's control; false, with the
/// particle kept at `previous` and marked failed (weight zero), when Sigma1 is not SPD or f is
/// not finite.
template <typename Ctx, typename Stats>
bool predict_particle(const Ctx& ctx, const robot::Pose& previous, robot::Pose& f,
                      robot::Mat3& sigma1_full, SmallFactor<3>& sigma1, robot::Pose& next,
                      Stats& st) {
  if (predict_pose(*ctx.motion, previous, ctx.u, f, sigma1_full, sigma1)) return true;
  st.failed = true;
  next = previous;
  return false;
}

/// The kernel's maps and weight (spec §1.2, §1.3) at the usable minimum nr of obj, with the
/// factor used at mu: the implicit proposals' sample x = map(xi) and its log weight (-inf, and
/// the particle marked failed, when it is not finite).
template <typename Objective, typename Map, typename Stats>
double sample_at_minimum(const Objective& obj, const NewtonMinimum<SmallFactor<3>>& nr, Map map,
                         const Vec<3>& xi, robot::Pose& next, Stats& st) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  double log_w = kNegInf;
  if (map == Map::kLinear) {
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

template <typename Motion, typename Observation, typename Stats>
double bootstrap_step(const ObservationContext<Motion, Observation>& ctx,
                      const robot::Pose& previous, Rng& rng, robot::Pose& next, Stats& st) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  robot::Pose f;
  robot::Mat3 sigma1_full;
  SmallFactor<3> sigma1;
  if (!predict_particle(ctx, previous, f, sigma1_full, sigma1, next, st)) return kNegInf;
  const Vec<3> xi = rng.normal_vector<3>();  // one call: argument order is unspecified
  next = f + sigma1.matrixL() * xi;
  if (ctx.z == nullptr) return 0.0;
  double log_w = 0.0;
  if constexpr (robot::CountingObservationModel<Observation>)
    log_w = ctx.observation->log_likelihood(*ctx.z, next, st);  // counts used and dropped parts
  else
    log_w = ctx.observation->log_likelihood(*ctx.z, next);
  if (std::isnan(log_w) || log_w == std::numeric_limits<double>::infinity()) {
    st.failed = true;
    return kNegInf;
  }
  return log_w;
}

/// The defensive mixture's sample (u < a: the prior's, else the implicit Gaussian's, both from
/// xi) and its log weight -F(x) - log q(x) (see the file comment).
template <typename Objective, typename Stats>
double defensive_sample(const Objective& obj, const NewtonMinimum<SmallFactor<3>>& nr,
                        const robot::Pose& f, const SmallFactor<3>& sigma1, double a, double u,
                        const Vec<3>& xi, robot::Pose& next, Stats& st) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  if (u < a) {
    next = f + sigma1.matrixL() * xi;
  } else {
    Vec<3> offset = xi;
    nr.factor.upper_solve_in_place(offset);
    next = nr.x + offset;
  }
  const double value = obj.evaluate(next);
  // log N(x; f, Sigma1) and log N(x; mu, H^-1), with H = L L^T: xi_H = L^T (x - mu).
  const Vec<3> eta = sigma1.solve_lower(next - f);
  const Vec<3> xi_h = nr.factor.matrixL().transpose() * (next - nr.x);
  const double log_prior = gaussian_log_density(3, sigma1.log_det_L(), eta.squaredNorm());
  const double log_implicit = gaussian_log_density(3, -nr.factor.log_det_L(), xi_h.squaredNorm());
  const double p = std::log(a) + log_prior, q = std::log1p(-a) + log_implicit;
  const double log_q = std::max(p, q) + std::log1p(std::exp(-std::abs(p - q)));
  const double log_w = -value - log_q;
  if (!std::isfinite(log_w)) {
    st.failed = true;
    return kNegInf;
  }
  return log_w;
}

template <typename Motion, typename Observation, typename Stats, typename Map>
double implicit_step(const ObservationContext<Motion, Observation>& ctx, Map map,
                     const NewtonOptions& newton, int starts, int probe, double defensive,
                     const robot::Pose& previous, Rng& rng, robot::Pose& next, Stats& st) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  robot::Pose f;
  robot::Mat3 sigma1_full;
  SmallFactor<3> sigma1;
  if (!predict_particle(ctx, previous, f, sigma1_full, sigma1, next, st)) return kNegInf;
  const Vec<3> xi = rng.normal_vector<3>();
  if (ctx.z == nullptr) {  // F is the Gaussian prior: mu = f, all weights equal
    next = f + sigma1.matrixL() * xi;
    return 0.0;
  }
  const robot::Mat3 prior_information = sigma1.inverse();
  const double constant = gaussian_log_normaliser(3, sigma1.log_det_L());
  PoseObjective<Observation> obj;
  obj.reset(*ctx.observation, *ctx.z, f, prior_information, constant);
  NewtonMinimum<SmallFactor<3>> nr = newton_minimize<SmallFactor<3>>(obj, f, newton);
  st.iterations += nr.evaluations;
  // Further starts drawn from the prior: the centre is the lowest minimum found. The weights
  // stay exact, since the starts are auxiliary randomness drawn before x and the weight divides
  // by the density of x given them (see the file comment). With a probe, each runs at most
  // `probe` iterations first and goes on only if it is already below the best value.
  NewtonOptions probing = newton;
  if (probe > 0) probing.max_iterations = std::min(probe, newton.max_iterations);
  const auto below_best = [&nr](const NewtonMinimum<SmallFactor<3>>& m) {
    return m.factor_ok && std::isfinite(m.value) &&
           (!nr.factor_ok || !std::isfinite(nr.value) || m.value < nr.value);
  };
  for (int k = 1; k < starts; ++k) {
    const Vec<3> eta = rng.normal_vector<3>();
    const robot::Pose x0 = f + sigma1.matrixL() * eta;
    NewtonMinimum<SmallFactor<3>> other = newton_minimize<SmallFactor<3>>(obj, x0, probing);
    st.iterations += other.evaluations;
    if (probe > 0 && other.status == MinimizeStatus::kMaxIterations && below_best(other)) {
      other = newton_minimize<SmallFactor<3>>(obj, other.x, newton);
      st.iterations += other.evaluations;
    }
    if (below_best(other)) nr = other;
  }
  st.fallback = st.fallback || !nr.exact_factor;
  const bool usable_minimum = nr.factor_ok && nr.status != MinimizeStatus::kNonFinite &&
                              std::isfinite(nr.value) && std::isfinite(nr.factor.log_det_L());
  if (!usable_minimum) {
    // No Gaussian approximation: sample the prior and weight by the likelihood (the bootstrap
    // fallback, still a valid proposal).
    st.fallback = true;
    next = f + sigma1.matrixL() * xi;
    const double lw = ctx.observation->log_likelihood(*ctx.z, next);
    if (!std::isfinite(lw)) {
      st.failed = true;
      return kNegInf;
    }
    return lw;
  }
  if (defensive > 0.0 && map == Map::kLinear) {
    const double u = rng.uniform();
    return defensive_sample(obj, nr, f, sigma1, defensive, u, xi, next, st);
  }
  return sample_at_minimum(obj, nr, map, xi, next, st);
}

}  // namespace detail
}  // namespace implicit::filter
