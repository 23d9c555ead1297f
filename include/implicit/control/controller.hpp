#pragma once
// The path integral controller: u = gamma R^-1 G^T grad log psi by central differences of an
// estimator (estimators.hpp) with common random numbers, and the receding-horizon closed loop.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "implicit/control/estimators.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

template <int P>
struct ControlEstimate {
  Vec<P> u = Vec<P>::Zero();
  PsiEstimate psi;        ///< at x
  bool defined = true;    ///< false if u could not be estimated (see fallback)
  bool fallback = false;  ///< log psi_hat was -inf at x or some x +- s g_j: u is the Laplace one
  MinimizeStatus worst_status = MinimizeStatus::kConverged;
};

/// u = gamma R^-1 G^T grad log psi_hat by central differences along the columns g_j of G with
/// common random numbers: the same reference variables at x + s g_j and x - s g_j (s |g_j| = h),
/// minimisers warm-started at mu(x). `warm` (a path y_1..y_n, e.g. the previous step's minimiser
/// shifted by one step) starts the minimisation at x; empty: the drift path. A wall at t_k is
/// behind the control (it moves only the states after t_k): the estimates ignore it
/// (WallSampling::test_start). When no sample passes at x or at some x +- s g_j, u
/// differentiates the Laplace approximation of psi instead (o.laplace_fallback; `fallback`), or
/// is left undefined (`defined` false).
template <typename Problem>
ControlEstimate<Problem::kControlDim> estimate_control(const Problem& problem,
                                                       const Vec<Problem::kStateDim>& x, int k,
                                                       const EstimatorOptions& o,
                                                       const StreamKey& key,
                                                       const Eigen::VectorXd& warm = {}) {
  constexpr int D = Problem::kStateDim;
  const std::vector<WallMode>* frozen = nullptr;
  // The references are drawn once, at x, and replayed at every x +- s g_j.
  ReplayableNormals references({key.seed, key.step, key.index, purpose::kReference});
  auto psi = [&](const Vec<D>& xp, const Eigen::VectorXd& start) {
    references.rewind();
    return o.method == PsiMethod::kImplicit
               ? estimate_log_psi_implicit(problem, xp, k, o.samples, key, start, o.minimize, o.map,
                                           frozen, &references, {o.modes, o.laplace_weights, false})
               : estimate_log_psi_monte_carlo(problem, xp, k, o.samples, key, false);
  };
  ControlEstimate<Problem::kControlDim> c;
  c.psi = psi(x, warm);
  if (o.freeze_walls && !c.psi.modes.empty()) frozen = &c.psi.modes;
  c.worst_status = c.psi.status;
  const double h = o.fd_step * (o.relative_fd_step ? std::max(1.0, x.cwiseAbs().maxCoeff()) : 1.0);
  // u needs G^T grad log psi only: one central difference along each column g_j of G (a step h
  // long), not along every state coordinate; with partial noise or P < D that is fewer estimates.
  constexpr int P = Problem::kControlDim;
  Vec<P> slope = Vec<P>::Zero(), laplace = Vec<P>::Zero();
  bool sampled = std::isfinite(c.psi.log_psi), laplace_ok = true;
  for (int j = 0; j < P; ++j) {
    const Vec<D> g = problem.spec().G.col(j);
    const double norm = g.norm();
    if (norm == 0.0) continue;  // control j moves nothing: its slope is zero
    const double s = h / norm;
    const Vec<D> xp = x + s * g, xm = x - s * g;
    const auto ep = psi(xp, c.psi.minimizer), em = psi(xm, c.psi.minimizer);
    if (ep.status != MinimizeStatus::kConverged) c.worst_status = ep.status;
    if (em.status != MinimizeStatus::kConverged) c.worst_status = em.status;
    sampled = sampled && std::isfinite(ep.log_psi) && std::isfinite(em.log_psi);
    slope(j) = (ep.log_psi - em.log_psi) / (2.0 * s);
    laplace_ok =
        laplace_ok && std::isfinite(ep.log_psi_laplace) && std::isfinite(em.log_psi_laplace);
    laplace(j) = (ep.log_psi_laplace - em.log_psi_laplace) / (2.0 * s);
  }
  if (!sampled) {
    c.fallback = o.laplace_fallback && laplace_ok;
    c.defined = c.fallback;
    slope = c.fallback ? laplace : Vec<P>::Zero();
  }
  c.u = problem.control_from_slopes(slope);
  return c;
}

/// Receding-horizon closed loop: x_{k+1} = x_k + (f + G u_k) dt + G Q sqrt(dt) W_k with the
/// noise realisation `noise` (D x K, columns W_k ~ N(0, I) mapped through Sigma^{1/2}). Each
/// step's minimisation starts from the previous step's minimiser without its first state.
template <typename Problem>
struct ClosedLoopResult {
  std::vector<Vec<Problem::kStateDim>> x;
  std::vector<Vec<Problem::kControlDim>> u;
  std::vector<PsiEstimate> psi;
  int fallbacks = 0;  ///< steps whose control is the Laplace one (no sample passed)
};

template <typename Problem>
ClosedLoopResult<Problem> simulate_closed_loop(const Problem& problem,
                                               const Vec<Problem::kStateDim>& x0,
                                               const Eigen::MatrixXd& noise,
                                               const EstimatorOptions& o, std::uint64_t seed,
                                               std::uint64_t run = 0) {
  constexpr int D = Problem::kStateDim;
  const int K = problem.num_steps();
  require(noise.rows() == D && noise.cols() == K,
          "closed loop: expected a {} x {} noise matrix, got {} x {}", D, K, noise.rows(),
          noise.cols());
  ClosedLoopResult<Problem> r;
  r.x.push_back(x0);
  const double sdt = std::sqrt(problem.dt());
  Eigen::VectorXd warm;  // the last minimiser without its first state: receding horizon
  for (int k = 0; k < K; ++k) {
    const auto c = estimate_control(problem, r.x.back(), k, o,
                                    {seed, run, static_cast<std::uint64_t>(k), 0}, warm);
    // The path from step k + 1 is the tail of the path from step k (without y_1 when it sat at
    // step k + 1: always on every step, only at a wall or the horizon otherwise). A path entry
    // holds the noisy coordinates only (all D of them unless the noise is partial).
    constexpr int B = Problem::kNoisyDim;
    const Eigen::Index rest = static_cast<Eigen::Index>(problem.path_length(k + 1)) * B;
    warm = c.psi.minimizer.size() == static_cast<Eigen::Index>(problem.path_length(k)) * B
               ? Eigen::VectorXd(c.psi.minimizer.tail(rest))
               : Eigen::VectorXd();
    r.u.push_back(c.u);
    r.psi.push_back(c.psi);
    r.fallbacks += c.fallback ? 1 : 0;
    const Vec<D>& x = r.x.back();
    const Vec<D> w = noise.col(k);
    r.x.push_back(
        x + (problem.model().drift(x, problem.time(k)) + problem.spec().G * c.u) * problem.dt() +
        problem.sigma_sqrt() * w * sdt);
  }
  return r;
}

}  // namespace implicit::control
