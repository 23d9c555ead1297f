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
#include "implicit/control/wall_modes.hpp"
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

/// How implicit sampling maps a reference sample xi to a path (spec §1.2, §1.3).
enum class SamplingMap {
  kLinear,  ///< y = mu + L^{-T} xi, weight exp(F_hat - F)
  kRandom,  ///< y = mu + lambda L^{-T} xi / |xi| with F(y) - phi = |xi|^2 / 2 (corrected Jacobian)
};

inline std::string_view to_string(SamplingMap m) {
  return m == SamplingMap::kLinear ? "linear" : "random";
}

/// One estimate of log psi with diagnostics.
struct PsiEstimate {
  double log_psi = -std::numeric_limits<double>::infinity();
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
  double fd_step = 1e-4;  ///< h = fd_step max(1, |x|_inf) for the central differences
  MinimizeOptions minimize{};
};

namespace detail {
inline PsiEstimate summarize(std::vector<double>& lw) {
  PsiEstimate e;
  e.samples = static_cast<int>(lw.size());
  for (double l : lw) e.wall_hits += std::isfinite(l) ? 0 : 1;
  e.log_psi = log_mean_exp(lw);
  if (e.wall_hits < e.samples) {
    std::vector<double> w(lw.size());
    e.ess = normalize_log_weights(lw, w).ess;
    e.relative_se = relative_standard_error(lw);
  }
  return e;
}

/// Implicit sampling of psi without walls ahead: minimise F from `start`, then M samples with
/// the linear or the random map from the reference stream `refs`.
template <typename Problem, typename PathF>
PsiEstimate sample_without_walls(const Problem& problem, const PathF& F,
                                 const Eigen::VectorXd& start, int M, ReplayableNormals& refs,
                                 const MinimizeOptions& options, SamplingMap map) {
  constexpr int D = Problem::kStateDim;
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int n = F.num_blocks(), N = n * D;
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
  const double log_norm = problem.log_normalizer(n);
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
  out.map_failures = failures;
  out.wall_hits -= failures;
  out.status = r.status;
  out.minimizer = std::move(r.x);
  return out;
}

/// The mixture proposal over the wall modes: each mode's constrained minimum, its banded factor
/// and log det L, and after normalise() the log mixture weights and their cumulative table.
template <int D>
struct WallMixture {
  std::vector<WallMode> modes;
  std::vector<BandedFactor<D>> factors;
  std::vector<double> log_det, log_pi, cumulative;
  double total = 0.0;  ///< the last cumulative weight (1 up to rounding)
  MinimizeStatus status = MinimizeStatus::kConverged;  ///< the worst mode's

  /// log pi_c = log_weight_c - log sum; false if every mode has weight 0.
  bool normalise() {
    log_pi.resize(modes.size());
    for (std::size_t c = 0; c < modes.size(); ++c) log_pi[c] = modes[c].log_weight;
    const double lse = log_sum_exp(log_pi);
    if (!std::isfinite(lse)) return false;
    cumulative.resize(modes.size());
    total = 0.0;
    for (std::size_t c = 0; c < modes.size(); ++c) {
      log_pi[c] -= lse;
      modes[c].log_weight = log_pi[c];
      total += std::exp(log_pi[c]);
      cumulative[c] = total;
    }
    return true;
  }
  /// The component for a uniform u in [0, 1), never one of weight 0.
  std::size_t choose(double u01) const {
    const double u = u01 * total;
    std::size_t c = 0;
    while (c + 1 < modes.size() && !(u < cumulative[c])) ++c;
    while (!std::isfinite(log_pi[c]) && c > 0) --c;
    return c;
  }
};

/// Finds every mode's constrained minimum (mode_minimum) and Laplace mass exp(-phi) / det L;
/// `frozen` keeps the given modes' wall values and mixture weights.
template <typename PathF, typename Problem>
WallMixture<PathF::Block> fit_wall_modes(const PathF& F, const WallsAhead<Problem>& w,
                                         const Eigen::VectorXd& start,
                                         const std::vector<WallMode>* frozen,
                                         const MinimizeOptions& options) {
  constexpr int D = PathF::Block;
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int A = w.size();
  WallMixture<D> mix;
  if (frozen) {
    mix.modes = *frozen;
    for (const auto& md : mix.modes)
      require(md.walls == w.ahead && md.minimizer.size() == start.size(),
              "path integral estimator: the frozen modes belong to another step or problem");
  } else {
    mix.modes = enumerate_modes(w);
  }
  // The unconstrained minimiser: the start of every mode's constrained search.
  Eigen::VectorXd free_min = start;
  if (!frozen) {
    const auto r = minimize_path(F, start, options);
    if (r.status != MinimizeStatus::kNonFinite) free_min = r.x;
  }
  mix.factors.resize(mix.modes.size());
  mix.log_det.assign(mix.modes.size(), 0.0);
  PathConstraints cons;
  for (std::size_t c = 0; c < mix.modes.size(); ++c) {
    WallMode& md = mix.modes[c];
    auto r = mode_minimum(F, w, md, free_min, frozen != nullptr, options, cons);
    md.status = r.status;
    md.minimizer = r.x;
    md.samples = 0;
    md.wall_hits = 0;
    md.wall_values.resize(static_cast<std::size_t>(A));
    for (int i = 0; i < A; ++i) md.wall_values[static_cast<std::size_t>(i)] = w.value(i, r.x);
    const bool usable = r.status != MinimizeStatus::kNonFinite && r.factor_ok;
    md.phi = usable ? r.value : std::numeric_limits<double>::infinity();
    if (usable) {
      mix.factors[c] = std::move(r.factor);
      mix.log_det[c] = mix.factors[c].log_det_L();
    }
    if (!frozen) md.log_weight = usable ? -md.phi - mix.log_det[c] : kNegInf;
    if (!usable) md.log_weight = kNegInf;
    if (md.status != MinimizeStatus::kConverged) mix.status = md.status;
  }
  return mix;
}

/// log q(y) / q_c(y) for the linear mixture q = sum_i pi_i N(mu_i, H_i^{-1}) at y = mu_c +
/// L_c^{-T} xi, drawn from component c: the weight of the mixture is the kernel's implicit weight
/// of component c divided by this ratio. Streamed, no allocation (`diff` is scratch).
template <int D>
double mixture_log_ratio(const WallMixture<D>& mix, const Eigen::VectorXd& y,
                         const Eigen::VectorXd& xi, std::size_t c, Eigen::VectorXd& diff) {
  // log(pi_i q_i(y) / q_c(y)); the (2 pi)^{-N/2} of the components cancels.
  const double log_q_c = mix.log_det[c] - 0.5 * xi.squaredNorm();
  double top = -std::numeric_limits<double>::infinity(), sum = 0.0;
  for (std::size_t i = 0; i < mix.modes.size(); ++i) {
    if (!std::isfinite(mix.log_pi[i])) continue;
    double t = mix.log_pi[i];
    if (i != c) {
      diff = y - mix.modes[i].minimizer;
      t += mix.log_det[i] - 0.5 * upper_norm2(mix.factors[i], diff) - log_q_c;
    }
    if (t > top) {
      sum = sum * std::exp(top - t) + 1.0;
      top = t;
    } else {
      sum += std::exp(t - top);
    }
  }
  return top + std::log(sum);
}

/// Random map inside mode c only: F restricted to the paths through c's openings (+inf
/// elsewhere), integrated along rays from mu_c. That region is convex and mu_c is the
/// constrained minimum, so for a convex F every ray sees F - phi_c increase: the map is
/// one-to-one onto the region. psi = sum_c Z_c, and choosing c with probability pi_c makes
/// w / pi_c unbiased for it. Writes the log weight (without the path normaliser) to `l`.
template <typename PathF, typename Problem>
RayStatus random_map_in_mode(const PathF& F, const WallsAhead<Problem>& w,
                             const WallMixture<PathF::Block>& mix, std::size_t c,
                             const Eigen::VectorXd& xi, Eigen::VectorXd& d,
                             std::vector<double>& a_mu, std::vector<double>& a_d, double& l) {
  constexpr int D = PathF::Block;
  const int A = w.size();
  const int N = static_cast<int>(xi.size());
  const double rho = xi.squaredNorm();
  d = xi / std::sqrt(rho);
  mix.factors[c].upper_solve_in_place(d);
  const WallMode& md = mix.modes[c];
  for (int i = 0; i < A; ++i) {
    const auto& a = w.wall(i).direction;
    const auto s = static_cast<std::size_t>(i);
    a_mu[s] = a.dot(md.minimizer.template segment<D>(w.block_of(i) * D));
    a_d[s] = a.dot(d.template segment<D>(w.block_of(i) * D));
  }
  // mu_c sits on the edge of an opening when that wall is clamped: a ray leaving through the
  // edge sees F = +inf for every lambda > 0, which the root finder reports as a jump at 0
  // (weight 0), like any other jump over the level.
  auto inside = [&](double lambda) {
    for (int i = 0; i < A; ++i)
      if (!w.opening(i, md).contains(a_mu[static_cast<std::size_t>(i)] +
                                     lambda * a_d[static_cast<std::size_t>(i)]))
        return false;
    return true;
  };
  const RestrictedPath restricted{F, inside};
  double lambda = 0.0, slope = 0.0;
  const double level = md.phi + 0.5 * rho;
  const auto ray = solve_path_ray(restricted, md.minimizer, d, level, rho, lambda, slope);
  if (ray == RayStatus::kOk)
    l = implicit_log_weight(N, rho, level, mix.log_det[c],
                            random_map_log_jacobian(N, rho, lambda, slope)) -
        mix.log_pi[c];
  return ray;
}

/// Implicit sampling of psi with walls ahead: a mixture over the wall modes (fit_wall_modes),
/// component choice from stream (key..., kMixture), references from `refs`.
template <typename Problem, typename PathF>
PsiEstimate sample_with_walls(const Problem& problem, const Vec<Problem::kStateDim>& x, int k,
                              const PathF& F, const WallsAhead<Problem>& w,
                              const Eigen::VectorXd& start, int M, const StreamKey& key,
                              ReplayableNormals& refs, const MinimizeOptions& options,
                              SamplingMap map, const std::vector<WallMode>* frozen) {
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  const int n = F.num_blocks(), N = static_cast<int>(start.size());
  auto mix = fit_wall_modes(F, w, start, frozen, options);
  if (!mix.normalise()) {
    PsiEstimate dead;  // psi = 0: every sample has zero weight
    dead.samples = M;
    dead.wall_hits = M;
    dead.status = mix.status;
    dead.modes = std::move(mix.modes);
    return dead;
  }
  Rng pick({key.seed, key.step, key.index, purpose::kMixture});
  const double log_norm = problem.log_normalizer(n);
  std::vector<double> lw(static_cast<std::size_t>(M));
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
      if (ray == RayStatus::kOk) {
        l -= log_norm;
      } else {
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
    const double fy = problem.passes_walls(x, k, y) ? F.evaluate(y, nullptr, nullptr)
                                                    : std::numeric_limits<double>::infinity();
    if (!std::isfinite(fy)) {
      ++mix.modes[c].wall_hits;
      l = kNegInf;
      continue;
    }
    l = implicit_log_weight(N, xi.squaredNorm(), fy, mix.log_det[c]) -
        mixture_log_ratio(mix, y, xi, c, diff) - log_norm;
  }
  PsiEstimate result = summarize(lw);
  result.map_failures = failures;
  result.wall_hits -= failures;
  result.status = mix.status;
  result.modes = std::move(mix.modes);
  const auto best = std::max_element(
      result.modes.begin(), result.modes.end(),
      [](const WallMode& a, const WallMode& b) { return a.log_weight < b.log_weight; });
  result.minimizer = best->minimizer;
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
template <typename Problem>
PsiEstimate estimate_log_psi_implicit(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                      int k, int M, const StreamKey& key,
                                      const Eigen::VectorXd& warm = {},
                                      const MinimizeOptions& options = {},
                                      SamplingMap map = SamplingMap::kLinear,
                                      const std::vector<WallMode>* frozen = nullptr,
                                      ReplayableNormals* references = nullptr) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 sample, got {}", M);
  const auto F = problem.path_function(x, k);
  const int N = F.num_blocks() * D;
  for (std::size_t j = 0; j < problem.walls().size(); ++j) {
    if (problem.wall_step(j) == k && !problem.walls()[j].passes(x)) {
      PsiEstimate dead;  // at the wall, outside an opening: psi = 0
      dead.samples = M;
      dead.wall_hits = M;
      return dead;
    }
  }
  const detail::WallsAhead<Problem> ahead(problem, k);
  require(warm.size() == 0 || warm.size() == N,
          "path integral estimator: expected a warm start of {} entries ({} steps of {} states) "
          "or none, got {}",
          N, F.num_blocks(), D, warm.size());
  const Eigen::VectorXd start = warm.size() == N ? warm : problem.drift_path(x, k);
  ReplayableNormals own({key.seed, key.step, key.index, purpose::kReference}, 0);
  ReplayableNormals& refs = references ? *references : own;
  if (ahead.size() == 0)
    return detail::sample_without_walls(problem, F, start, M, refs, options, map);
  return detail::sample_with_walls(problem, x, k, F, ahead, start, M, key, refs, options, map,
                                   frozen);
}

/// log psi_hat(x, t_k) by plain Monte Carlo: M forward-Euler paths, path j from stream
/// (key.seed, key.step, key.index * M + j, kProposal). Hard walls zero the paths that miss them.
template <typename Problem>
PsiEstimate estimate_log_psi_monte_carlo(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                         int k, int M, const StreamKey& key) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 path, got {}", M);
  const auto F = problem.path_function(x, k);  // validates k and x
  const int n = F.num_blocks();
  const double dt = problem.dt(), g = problem.gamma();
  const Mat<D> scale = problem.sigma_sqrt() * std::sqrt(dt);
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd path(n * D);
  const bool walled = !problem.walls().empty();
  for (int j = 0; j < M; ++j) {
    Rng rng(
        {key.seed, key.step, key.index * static_cast<std::uint64_t>(M) + j, purpose::kProposal});
    Vec<D> y = x;
    double cost = 0.5 * dt * problem.model().running_cost(y, problem.time(k));
    for (int i = 1; i <= n; ++i) {
      y = y + problem.model().drift(y, problem.time(k + i - 1)) * dt +
          scale * rng.normal_vector<D>();
      if (walled) path.template segment<D>((i - 1) * D) = y;
      cost += (i == n ? 0.5 : 1.0) * dt * problem.model().running_cost(y, problem.time(k + i));
    }
    cost += problem.model().final_cost(y);
    if (walled && !problem.passes_walls(x, k, path)) cost = std::numeric_limits<double>::infinity();
    lw[static_cast<std::size_t>(j)] =
        std::isfinite(cost) ? -cost / g : -std::numeric_limits<double>::infinity();
  }
  return detail::summarize(lw);
}

}  // namespace implicit::control
