#pragma once
// The Gaussian mixture over the wall modes (wall_modes.hpp) that the estimators of psi sample
// with hard walls ahead: each mode's constrained minimum, factor and Laplace mass; the mixture's
// density ratio; the random map restricted to one mode's openings; the Laplace approximation.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "implicit/control/path_solvers.hpp"
#include "implicit/control/wall_modes.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::control::detail {

/// The mixture proposal over the wall modes: each mode's constrained minimum, its banded factor
/// and log det L, and after normalise() the log mixture weights and their cumulative table.
template <int D>
struct WallMixture {
  std::vector<WallMode> modes;
  std::vector<BandedFactor<D>> factors;
  std::vector<double> log_det, log_pi, cumulative;
  std::vector<Eigen::VectorXd> gradients;  ///< grad F at each minimum
  std::vector<char> exact;                 ///< the factor is the Hessian's own (not damped)
  double total = 0.0;                      ///< the last cumulative weight (1 up to rounding)
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
/// `frozen` keeps the given modes' wall values and mixture weights; `convex` (a linear-quadratic
/// problem) searches each mode from the free minimiser only (mode_minimum).
template <typename PathF, typename Problem>
WallMixture<PathF::Block> fit_wall_modes(const PathF& F, const WallsAhead<Problem>& w,
                                         const Eigen::VectorXd& start,
                                         const std::vector<WallMode>* frozen,
                                         const MinimizeOptions& options, bool convex = false) {
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
  mix.gradients.resize(mix.modes.size());
  mix.exact.assign(mix.modes.size(), 0);
  PathConstraints cons;
  for (std::size_t c = 0; c < mix.modes.size(); ++c) {
    WallMode& md = mix.modes[c];
    auto r = mode_minimum(F, w, md, free_min, frozen != nullptr, options, cons, convex);
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
      mix.gradients[c] = std::move(r.gradient);
      mix.exact[c] = r.exact_factor ? 1 : 0;
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

/// True if the path y passes every wall ahead through the openings of mode `md`.
template <typename Problem>
bool inside_mode(const WallsAhead<Problem>& w, const WallMode& md, const Eigen::VectorXd& y) {
  for (int i = 0; i < w.size(); ++i)
    if (!w.opening(i, md).contains(w.value(i, y))) return false;
  return true;
}

/// The Laplace approximation of psi (times the path normaliser) over the modes `used`.
template <int D>
double laplace_log_mass(const WallMixture<D>& mix, const std::vector<std::size_t>& used, int N) {
  std::vector<double> l;
  for (std::size_t c : used)
    l.push_back(implicit_log_weight(N, 0.0, mix.modes[c].phi, mix.log_det[c]));
  return l.empty() ? -std::numeric_limits<double>::infinity() : log_sum_exp(l);
}

}  // namespace implicit::control::detail
