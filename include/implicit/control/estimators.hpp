#pragma once
// Estimators of log psi for the generic problem (problem.hpp): implicit sampling over the path
// (banded Newton, then the linear or the random map; with hard walls a Gaussian mixture over
// the wall modes of wall_modes.hpp) and plain Monte Carlo over forward-Euler paths.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "implicit/control/path_solvers.hpp"
#include "implicit/control/wall_mixture.hpp"
#include "implicit/control/wall_modes.hpp"
#include "implicit/control/wall_values.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::control {

enum class PsiMethod {
  kImplicit,    ///< implicit sampling over the path: banded Newton + linear or random map
  kMonteCarlo,  ///< plain Monte Carlo over forward-Euler paths
};

/// How implicit sampling maps a reference sample xi to a path (core/types.hpp).
using SamplingMap = MapKind;

inline std::string_view to_string(SamplingMap m) {
  return m == SamplingMap::kLinear ? "linear" : "random";
}

/// With hard walls ahead: which wall modes (wall_modes.hpp) draw the samples.
enum class ModeSampling {
  /// M samples from the Gaussian mixture of all modes, weighted by exp(-F) / q (the default).
  kMixture,
  /// M samples from every mode; a sample counts only inside its own mode's openings. The modes'
  /// regions are disjoint, so psi is the sum of the modes' means (spec §2.4.4, W2).
  kEachMode,
  /// M samples from the mode of largest Laplace mass only: estimates that mode's share of psi
  /// (spec §2.4.4, W1; with EstimatorOptions::laplace_weights the paper's estimator P).
  kDominant,
};

/// One estimate of log psi with diagnostics.
struct PsiEstimate {
  double log_psi = -std::numeric_limits<double>::infinity();
  /// log of the Laplace approximation of psi over the modes sampled (the Gaussian mass at each
  /// minimum): what the controller differentiates when no sample passed (laplace_fallback).
  double log_psi_laplace = -std::numeric_limits<double>::infinity();
  double ess = 0.0;
  int samples = 0;
  int wall_hits = 0;     ///< samples with F = +inf or outside a wall opening (zero weight)
  int map_failures = 0;  ///< random map: samples whose scalar equation had no root (zero weight)
  double relative_se = 0.0;  ///< sd(w) / (sqrt(M) mean w): the SE of log psi_hat, to first order
  MinimizeStatus status = MinimizeStatus::kConverged;  ///< of the minimiser (worst mode with walls)
  Eigen::VectorXd minimizer;    ///< mu (implicit only): warm start for nearby states
  std::vector<WallMode> modes;  ///< with hard walls ahead: the mixture components
};

struct EstimatorOptions {
  int samples = 50;
  PsiMethod method = PsiMethod::kImplicit;
  SamplingMap map = SamplingMap::kLinear;
  /// With hard walls: at x +- h keep each mode's wall values a^T y_w and mixture weights from x
  /// (spec §2.4.5, "frozen wall"). Still an exact importance sampler, and a sample cannot switch
  /// between passing and hitting the wall between x + h and x - h (that switch makes the finite
  /// difference spike).
  bool freeze_walls = true;
  double fd_step = 1e-4;         ///< h = fd_step max(1, |x|_inf) for the central differences
  bool relative_fd_step = true;  ///< false: h = fd_step whatever x
  MinimizeOptions minimize{};
  ModeSampling modes = ModeSampling::kMixture;  ///< with hard walls ahead
  /// The paper's biased estimator (spec §2.4.4, P): a sample inside its mode's openings weighs
  /// exp(-phi) of that mode instead of exp(-F(y) + |xi|^2 / 2). Only to reproduce the paper's
  /// tables; needs the linear map and ModeSampling::kEachMode or kDominant.
  bool laplace_weights = false;
  /// When log psi_hat is -inf at x or at some x +- h (no sample passed), differentiate the
  /// Laplace approximation instead (ControlEstimate::fallback); otherwise u is left undefined.
  bool laplace_fallback = true;
};

/// How the estimator of psi treats the walls and their modes (from EstimatorOptions).
struct WallSampling {
  ModeSampling modes = ModeSampling::kMixture;
  bool laplace_weights = false;
  /// A wall at t_k tests x itself (psi = 0 outside its openings). The controller turns this off:
  /// u_k moves only the states after t_k, so a wall at t_k is behind it (spec §2.4.6: a run that
  /// misses the slits at t1 goes on with the control for t >= t1).
  bool test_start = true;
};

namespace detail {
inline PsiEstimate summarize(const std::vector<double>& lw) {
  PsiEstimate e;
  e.samples = static_cast<int>(lw.size());
  for (double l : lw) e.wall_hits += std::isfinite(l) ? 0 : 1;
  const WeightMoments m = weight_moments(lw);  // one pass of exponentials: this is hot
  e.log_psi = m.log_mean;
  if (e.wall_hits < e.samples) {
    e.ess = m.ess;
    e.relative_se = m.relative_se;
  }
  return e;
}

/// Implicit sampling of psi without walls ahead: minimise F from `start`, then M samples with
/// the linear or the random map from the reference stream `refs`.
template <typename Problem, typename PathF>
PsiEstimate sample_without_walls(const Problem& problem, const PathF& F,
                                 const Eigen::VectorXd& start, int M, ReplayableNormals& refs,
                                 const MinimizeOptions& options, SamplingMap map) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int N = F.dimension();
  auto r = minimize_path(F, start, options);
  if (r.status == MinimizeStatus::kNonFinite || !r.factor_ok) {
    PsiEstimate dead;  // psi = 0: every sample has zero weight
    dead.samples = M;
    dead.wall_hits = M;
    dead.status = r.status;
    dead.minimizer = r.x;
    return dead;
  }
  // The weights are the kernel's implicit weights of exp(-F), divided by the normaliser of the
  // path measure (spec §2.2): psi = Z / normaliser.
  const double log_norm = problem.path_log_normalizer(F.start_step());
  const double laplace = implicit_log_weight(N, 0.0, r.value, r.factor.log_det_L()) - log_norm;
  if constexpr (declares_linear_quadratic<typename Problem::ModelType>()) {
    if (map == SamplingMap::kLinear && r.exact_factor && r.converged()) {
      // F is quadratic and mu its minimum: every linear-map weight is this Laplace value, so
      // drawing the samples would change nothing but rounding. The model's word is checked at
      // y = mu + L^{-T} e_0 (where d^T H d = 1).
      Eigen::VectorXd d = Eigen::VectorXd::Unit(N, 0);
      r.factor.upper_solve_in_place(d);
      require_quadratic(F, r.x, r.value, r.gradient, d, 1.0);
      PsiEstimate e;
      e.samples = M;
      e.ess = M;
      e.relative_se = 0.0;
      e.log_psi = e.log_psi_laplace = laplace;
      e.status = r.status;
      e.minimizer = std::move(r.x);
      return e;
    }
  }
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd xi(N), y(N);
  int failures = 0;
  if (map == SamplingMap::kLinear) {
    for (int j = 0; j < M; ++j) {
      refs.next(xi);
      lw[static_cast<std::size_t>(j)] = linear_map(F, r.x, r.factor, xi, y) - log_norm;
    }
  } else {
    for (int j = 0; j < M; ++j) {
      refs.next(xi);
      const double rho = xi.squaredNorm();
      // The ray direction d = L^{-T} xi / |xi|, in xi's storage (xi is not needed after rho; an
      // assignment to a second vector trips GCC 12's -Wuse-after-free inside Eigen).
      Eigen::VectorXd& d = xi;
      d /= std::sqrt(rho);
      r.factor.upper_solve_in_place(d);
      const double level = r.value + 0.5 * rho;
      double lambda = 0.0, slope = 0.0;
      const auto out = solve_path_ray(F, r.x, d, level, rho, lambda, slope);
      failures += out == RayStatus::kOk || out == RayStatus::kJump ? 0 : 1;
      lw[static_cast<std::size_t>(j)] =
          out == RayStatus::kOk
              ? implicit_log_weight(N, rho, level, r.factor.log_det_L(),
                                    random_map_log_jacobian(N, rho, lambda, slope)) -
                    log_norm
              : kNegInf;
    }
  }
  PsiEstimate out = summarize(lw);
  out.log_psi_laplace = laplace;
  out.map_failures = failures;
  out.wall_hits -= failures;
  out.status = r.status;
  out.minimizer = std::move(r.x);
  return out;
}

/// Stratified over the modes (ModeSampling::kEachMode, or kDominant with `used` one mode): M
/// samples from each mode c in `used`; a sample counts only inside c's own openings, so each
/// mode's mean estimates its own share psi_c and their sum estimates psi. Appends M log weights
/// per mode (without the path normaliser) to `lw`; returns the random map's failures.
template <typename PathF, typename Problem>
int sample_each_mode(const PathF& F, const WallsAhead<Problem>& w, WallMixture<PathF::Block>& mix,
                     const std::vector<std::size_t>& used, int M, ReplayableNormals& refs,
                     SamplingMap map, bool laplace_weights, std::vector<double>& lw) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int N = static_cast<int>(mix.modes.front().minimizer.size());
  Eigen::VectorXd xi(N), y(N), d(N);
  std::vector<double> a_mu(static_cast<std::size_t>(w.size())),
      a_d(static_cast<std::size_t>(w.size()));
  int failures = 0;
  for (std::size_t c : used) {
    WallMode& md = mix.modes[c];
    for (int j = 0; j < M; ++j) {
      refs.next(xi);
      ++md.samples;
      double l = kNegInf;
      if (map == SamplingMap::kRandom) {
        const auto ray = random_map_in_mode(F, w, mix, c, xi, d, a_mu, a_d, l);
        if (ray == RayStatus::kOk)
          l += mix.log_pi[c];  // the mode was not chosen at random: no 1 / pi_c
        else if (ray == RayStatus::kJump)
          ++md.wall_hits;
        else
          ++failures;
        lw.push_back(ray == RayStatus::kOk ? l : kNegInf);
        continue;
      }
      y = xi;
      mix.factors[c].upper_solve_in_place(y);
      y += md.minimizer;
      const double rho = xi.squaredNorm();
      if (inside_mode(w, md, y)) {
        const double fy = laplace_weights ? md.phi + 0.5 * rho : F.evaluate(y, nullptr, nullptr);
        l = implicit_log_weight(N, rho, fy, mix.log_det[c]);
      }
      if (!std::isfinite(l)) ++md.wall_hits;
      lw.push_back(l);
    }
  }
  return failures;
}

/// M samples from the mixture over the wall modes, component choice from `pick`: the log weights
/// exp(-F) / q (without the path normaliser) to `lw`; returns the random map's failures.
template <typename Problem, typename PathF>
int sample_mixture(const PathF& F, const WallsAhead<Problem>& w, WallMixture<PathF::Block>& mix,
                   int M, Rng& pick, ReplayableNormals& refs, SamplingMap map,
                   std::vector<double>& lw) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int N = static_cast<int>(mix.modes.front().minimizer.size());
  lw.resize(static_cast<std::size_t>(M));
  Eigen::VectorXd xi(N), y(N), diff(N), d(N);
  int failures = 0;
  std::vector<double> a_mu(static_cast<std::size_t>(w.size())),
      a_d(static_cast<std::size_t>(w.size()));
  for (int j = 0; j < M; ++j) {
    const std::size_t c = mix.choose(pick.uniform());
    refs.next(xi);
    ++mix.modes[c].samples;
    double& l = lw[static_cast<std::size_t>(j)];
    if (map == SamplingMap::kRandom) {
      const auto ray = random_map_in_mode(F, w, mix, c, xi, d, a_mu, a_d, l);
      if (ray != RayStatus::kOk) {
        if (ray == RayStatus::kJump)
          ++mix.modes[c].wall_hits;
        else
          ++failures;
        l = kNegInf;
      }
      continue;
    }
    y = xi;
    mix.factors[c].upper_solve_in_place(y);
    y += mix.modes[c].minimizer;
    // Walls at step k tested x before sampling; those behind do not count.
    const double fy =
        w.passes(y) ? F.evaluate(y, nullptr, nullptr) : std::numeric_limits<double>::infinity();
    if (!std::isfinite(fy)) {
      ++mix.modes[c].wall_hits;
      l = kNegInf;
      continue;
    }
    l = implicit_log_weight(N, xi.squaredNorm(), fy, mix.log_det[c]) -
        mixture_log_ratio(mix, y, xi, c, diff);
  }
  return failures;
}

/// Implicit sampling of psi with walls ahead over the wall modes (fit_wall_modes): a mixture
/// (component choice from stream (key..., kMixture)) or stratified over the modes
/// (sample_each_mode), references from `refs`.
template <typename Problem, typename PathF>
PsiEstimate sample_with_walls(const Problem& problem, const PathF& F, const WallsAhead<Problem>& w,
                              const Eigen::VectorXd& start, int M, const StreamKey& key,
                              ReplayableNormals& refs, const MinimizeOptions& options,
                              SamplingMap map, const std::vector<WallMode>* frozen,
                              const WallSampling& ws) {
  const int N = static_cast<int>(start.size());
  auto mix = fit_wall_modes(F, w, start, frozen, options,
                            declares_linear_quadratic<typename Problem::ModelType>());
  if (!mix.normalise()) {
    PsiEstimate dead;  // psi = 0: every sample has zero weight
    dead.samples = M;
    dead.wall_hits = M;
    dead.status = mix.status;
    dead.modes = std::move(mix.modes);
    return dead;
  }
  const std::size_t best = static_cast<std::size_t>(
      std::max_element(mix.log_pi.begin(), mix.log_pi.end()) - mix.log_pi.begin());
  std::vector<std::size_t> used;
  for (std::size_t c = 0; c < mix.modes.size(); ++c)
    if (std::isfinite(mix.log_pi[c]) && (ws.modes != ModeSampling::kDominant || c == best))
      used.push_back(c);
  const double log_norm = problem.path_log_normalizer(F.start_step());
  std::vector<double> lw;
  int failures = 0;
  double log_count = 0.0;  // stratified: psi_hat is the sum of the modes' means
  if (ws.modes == ModeSampling::kMixture) {
    Rng pick({key.seed, key.step, key.index, purpose::kMixture});
    failures = sample_mixture(F, w, mix, M, pick, refs, map, lw);
  } else {
    // Linear-quadratic problems need only the wall values (wall_values.hpp).
    bool done = false;
    if constexpr (declares_linear_quadratic<typename Problem::ModelType>())
      done = map == SamplingMap::kLinear &&
             sample_wall_values(F, w, mix, used, M, refs, ws.laplace_weights, lw);
    if (!done) failures = sample_each_mode(F, w, mix, used, M, refs, map, ws.laplace_weights, lw);
    log_count = std::log(static_cast<double>(used.size()));
  }
  for (double& l : lw) l -= log_norm;
  PsiEstimate result = summarize(lw);
  result.log_psi += log_count;
  result.log_psi_laplace = laplace_log_mass(mix, used, N) - log_norm;
  result.map_failures = failures;
  result.wall_hits -= failures;
  result.status = mix.status;
  result.modes = std::move(mix.modes);
  result.minimizer = result.modes[best].minimizer;
  return result;
}
}  // namespace detail

/// log psi_hat(x, t_k) by implicit sampling: minimise F (warm start `warm` if non-empty, else the
/// drift path), factor its banded Hessian (damped until SPD if needed: the weights stay exact),
/// then M samples with xi from stream (key.seed, key.step, key.index, kReference): the linear
/// map y = mu + L^{-T} xi, or the random map (spec §1.3, corrected Jacobian) along the ray
/// L^{-T} xi. Reusing the same key at a nearby x gives common random numbers.
///
/// With hard walls ahead (problem.walls() after t_k): one mode per combination of openings, each
/// with its constrained minimum (wall_modes.hpp), a Gaussian mixture over them weighted
/// by their Laplace masses, component choice from stream (..., kMixture), weights
/// exp(-F) / q with the true F (0 at a wall). `frozen` (from an estimate at a nearby x) keeps
/// that estimate's modes: their wall values a^T y_w and mixture weights. With the random map
/// and walls, a sample chooses mode c with probability pi_c and runs the random map of F
/// restricted to c's openings; its weight is divided by pi_c (the random map has no proposal
/// density in closed form, so the modes cannot share samples as the linear mixture does).
/// `references` (rewound, on the stream of `key` with purpose kReference) replays references
/// drawn for an earlier estimate instead of drawing them again: the same numbers, faster.
/// `walls` chooses how the modes draw samples (ModeSampling) and the paper's Laplace weights;
/// the random map cannot take Laplace weights, and they need stratified modes (InvalidArgument).
template <typename Problem>
PsiEstimate estimate_log_psi_implicit(
    const Problem& problem, const Vec<Problem::kStateDim>& x, int k, int M, const StreamKey& key,
    const Eigen::VectorXd& warm = {}, const MinimizeOptions& options = {},
    SamplingMap map = SamplingMap::kLinear, const std::vector<WallMode>* frozen = nullptr,
    ReplayableNormals* references = nullptr, const WallSampling& walls = {}) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 sample, got {}", M);
  require(!walls.laplace_weights ||
              (map == SamplingMap::kLinear && walls.modes != ModeSampling::kMixture),
          "path integral estimator: Laplace weights (the paper's estimator) need the linear map "
          "and stratified modes (ModeSampling::kEachMode or kDominant)");
  const auto F = problem.path_function(x, k);
  const int N = F.dimension();
  for (std::size_t j = 0; j < problem.walls().size(); ++j) {
    if (walls.test_start && problem.wall_step(j) == k && !problem.walls()[j].passes(x)) {
      PsiEstimate dead;  // at the wall, outside an opening: psi = 0
      dead.samples = M;
      dead.wall_hits = M;
      return dead;
    }
  }
  const detail::WallsAhead<Problem> ahead(problem, k);
  require(warm.size() == 0 || warm.size() == N,
          "path integral estimator: expected a warm start of {} entries ({} steps of {} path "
          "coordinates) or none, got {}",
          N, F.num_blocks(), Problem::kNoisyDim, warm.size());
  const Eigen::VectorXd start = warm.size() == N ? warm : problem.drift_path(x, k);
  ReplayableNormals own({key.seed, key.step, key.index, purpose::kReference}, 0);
  ReplayableNormals& refs = references ? *references : own;
  if constexpr (Problem::kNoisyDim < D) {  // no walls with partial noise (the constructor's check)
    return detail::sample_without_walls(problem, F, start, M, refs, options, map);
  } else {
    if (ahead.size() == 0)
      return detail::sample_without_walls(problem, F, start, M, refs, options, map);
    return detail::sample_with_walls(problem, F, ahead, start, M, key, refs, options, map, frozen,
                                     walls);
  }
}

/// log psi_hat(x, t_k) by plain Monte Carlo: M forward-Euler paths, path j from stream
/// (key.seed, key.step, key.index * M + j, kProposal). Hard walls zero the paths that miss them
/// (a wall at t_k tests x unless `test_start` is false, as in WallSampling).
template <typename Problem>
PsiEstimate estimate_log_psi_monte_carlo(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                         int k, int M, const StreamKey& key,
                                         bool test_start = true) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 path, got {}", M);
  const auto F = problem.path_function(x, k);  // validates k and x
  const int n = F.num_blocks();
  const int* steps = problem.path_steps(k);
  const double g = problem.gamma();
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd path(n * D);
  const bool walled = !problem.walls().empty();
  for (int j = 0; j < M; ++j) {
    Rng rng(
        {key.seed, key.step, key.index * static_cast<std::uint64_t>(M) + j, purpose::kProposal});
    Vec<D> y = x;
    // Trapezoid rule for the running cost over the resolved times (dt on every step).
    double cost = 0.0, before = 0.0;
    for (int i = 1, from = k; i <= n; from = steps[i - 1], ++i) {
      const double dt = (steps[i - 1] - from) * problem.dt();
      cost += 0.5 * (before + dt) * problem.model().running_cost(y, problem.time(from));
      y = y + problem.model().drift(y, problem.time(from)) * dt +
          problem.sigma_sqrt() * std::sqrt(dt) * rng.normal_vector<D>();
      if (walled) path.template segment<D>((i - 1) * D) = y;
      before = dt;
    }
    cost += 0.5 * before * problem.model().running_cost(y, problem.time(steps[n - 1]));
    cost += problem.model().final_cost(y);
    if (walled && !problem.passes_walls(x, k, path, test_start))
      cost = std::numeric_limits<double>::infinity();
    lw[static_cast<std::size_t>(j)] =
        std::isfinite(cost) ? -cost / g : -std::numeric_limits<double>::infinity();
  }
  return detail::summarize(lw);
}

}  // namespace implicit::control
