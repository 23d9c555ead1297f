// Damped Newton for all particles in lockstep: core's newton_minimize() (core/newton.hpp) with
// its objective calls batched across particles, so a Python F is called once per iteration (and
// once per round of up to eight backtracks) instead of once per particle and point.
//
// Per particle the rules are newton_minimize()'s without constraints: factor the exact Hessian,
// else Levenberg damping (detail::factor_with_fallback, the same code), else steepest descent;
// stop on the gradient, the Newton decrement, the step size or a small full step; Armijo
// backtracking whose first trial is evaluated with derivatives and the others values only
// (several per call, scanned in order: the same accepted step); a non-finite F is a failed trial.
// The loop differs only in that each stage runs for every unfinished particle before the next
// stage starts.

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/parallel.hpp"
#include "user_model.hpp"

namespace implicit::python::ssm {
namespace {

/// One particle's Newton state between the batched evaluations.
struct State {
  NewtonPoint point;
  VecX gradient, step;
  MatX hessian, damped;
  double slope = 0.0, size = 0.0, x_scale = 1.0, t = 1.0, full_value = 0.0;
  bool exact = true, factor_current = false, done = false, accepted = false;
};

bool finite_derivatives(const Evaluation& e, std::size_t r) {
  return e.gradient.row(static_cast<Eigen::Index>(r)).allFinite() &&
         e.hessian.row(static_cast<Eigen::Index>(r)).allFinite();
}

/// Factors the Hessian at the particle's point and sets its step, or ends the particle by the
/// stopping rules (newton_minimize's order: converged before the iteration limit).
void plan_step(State& s, const NewtonOptions& o) {
  NewtonPoint& p = s.point;
  p.factor_ok = detail::factor_with_fallback(p.factor, s.hessian, static_cast<MatX*>(nullptr),
                                             s.damped, s.exact, o.damping);
  s.factor_current = true;
  if (!p.factor_ok && !o.damping) {
    p.status = MinimizeStatus::kNotPositiveDefinite;
    s.done = true;
    return;
  }
  s.step = s.gradient;
  if (p.factor_ok) p.factor.solve_in_place(s.step);
  s.step = -s.step;
  const double grad_max = s.gradient.cwiseAbs().maxCoeff();
  s.size = s.step.cwiseAbs().maxCoeff();
  s.x_scale = o.relative_step_tolerance ? 1.0 + p.x.cwiseAbs().maxCoeff() : 1.0;
  s.slope = s.gradient.dot(s.step);
  const bool small_decrement = o.decrement_tolerance > 0.0 && -s.slope < o.decrement_tolerance;
  if (grad_max <= o.gradient_tolerance || small_decrement ||
      s.size <= o.step_tolerance * s.x_scale) {
    p.status = MinimizeStatus::kConverged;
    s.done = true;
    return;
  }
  if (p.iterations >= o.max_iterations) {
    p.status = MinimizeStatus::kMaxIterations;
    s.done = true;
    return;
  }
  if (!(s.slope < 0.0)) {
    s.step = -s.gradient;
    s.slope = -s.gradient.squaredNorm();
  }
  s.t = 1.0;
  s.accepted = false;
}

enum class Trial { kAccepted, kEnded, kNext };

/// newton_minimize's verdict on trial k (step length s.t) with value ft: Armijo's sufficient
/// decrease accepts it; the round-off floor or the last backtrack ends the particle (keeping x
/// and its factor); otherwise the next, halved, step is tried.
Trial judge(State& s, double ft, int k, const NewtonOptions& o) {
  NewtonPoint& p = s.point;
  const double value = p.value;
  if (std::isfinite(ft) && ft <= value + o.armijo * s.t * s.slope) return Trial::kAccepted;
  const double ulp = 8.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(value));
  const bool at_floor = std::isfinite(ft) && std::abs(ft - value) <= ulp && -s.slope * s.t <= ulp;
  if (at_floor || k == o.max_backtracks) {
    p.status = at_floor || s.size <= 1e3 * o.step_tolerance * s.x_scale
                   ? MinimizeStatus::kConverged
                   : MinimizeStatus::kLineSearchFailed;
    s.done = true;
    return Trial::kEnded;
  }
  s.t *= 0.5;
  return Trial::kNext;
}

/// Backtracks evaluated per particle in one call after the full step: the sequential rule
/// takes the first acceptable length of t, t/2, t/4, ...; evaluating eight of them at once and
/// scanning them in that order takes the same one, with an eighth of the Python calls.
constexpr int kTrialsPerCall = 8;

/// Armijo backtracking for every particle in `live` at once; afterwards s.accepted says whether
/// the particle moved (to p.x). The full step is evaluated with derivatives (into `full`, one
/// row per particle of `live`), the backtracks values only, kTrialsPerCall per call.
void line_search(BatchObjective& f, std::vector<State>& states, std::vector<std::size_t> live,
                 const NewtonOptions& o, Evaluation& full) {
  const Eigen::Index d = states[live.front()].point.x.size();
  Evaluation e;
  for (int k = 0; k <= o.max_backtracks && !live.empty();) {
    const int m = k == 0 ? 1 : std::min(kTrialsPerCall, o.max_backtracks - k + 1);
    RowMatrix trial(static_cast<Eigen::Index>(live.size()) * m, d);
    std::vector<std::size_t> owner;
    owner.reserve(live.size() * static_cast<std::size_t>(m));
    for (std::size_t r = 0; r < live.size(); ++r) {
      const State& s = states[live[r]];
      double t = s.t;
      for (int i = 0; i < m; ++i, t *= 0.5) {
        trial.row(static_cast<Eigen::Index>(r) * m + i) = (s.point.x + t * s.step).transpose();
        owner.push_back(live[r]);
      }
    }
    f.evaluate(owner, trial, k == 0 ? Derivatives::kHessian : Derivatives::kNone,
               k == 0 ? full : e);
    const Evaluation& got = k == 0 ? full : e;
    std::vector<std::size_t> next;
    for (std::size_t r = 0; r < live.size(); ++r) {
      State& s = states[live[r]];
      Trial verdict = Trial::kNext;
      for (int i = 0; i < m && verdict == Trial::kNext; ++i) {
        const Eigen::Index row = static_cast<Eigen::Index>(r) * m + i;
        const double ft = got.value[row];
        if (k == 0) s.full_value = ft;
        verdict = judge(s, ft, k + i, o);
        if (verdict == Trial::kAccepted) {
          s.accepted = true;
          s.point.x = trial.row(row).transpose();
        }
      }
      if (verdict == Trial::kNext) next.push_back(live[r]);
    }
    k += m;
    live = std::move(next);
  }
}

/// Row of particle j in the first-trial evaluation of `live` (live is ascending).
std::size_t row_of(const std::vector<std::size_t>& live, std::size_t j) {
  return static_cast<std::size_t>(std::lower_bound(live.begin(), live.end(), j) - live.begin());
}

}  // namespace

std::vector<NewtonPoint> lockstep_newton(BatchObjective& f, const RowMatrix& x0,
                                         const NewtonOptions& o) {
  const std::size_t n = static_cast<std::size_t>(x0.rows());
  std::vector<State> states(n);
  std::vector<std::size_t> all(n);
  for (std::size_t j = 0; j < n; ++j) {
    all[j] = j;
    states[j].point.x = x0.row(static_cast<Eigen::Index>(j)).transpose();
  }
  Evaluation e;
  f.evaluate(all, x0, Derivatives::kHessian, e);
  for (std::size_t j = 0; j < n; ++j) {
    State& s = states[j];
    s.point.value = e.value[static_cast<Eigen::Index>(j)];
    if (!std::isfinite(s.point.value) || !finite_derivatives(e, j)) {
      s.point.status = MinimizeStatus::kNonFinite;
      s.done = true;
      continue;
    }
    s.gradient = e.gradient.row(static_cast<Eigen::Index>(j)).transpose();
    s.hessian = e.hessian_at(static_cast<Eigen::Index>(j));
  }
  for (;;) {
    std::vector<std::size_t> live;
    for (std::size_t j = 0; j < n; ++j)
      if (!states[j].done) live.push_back(j);
    parallel_for(
        live.size(), [&](std::size_t r) { plan_step(states[live[r]], o); }, 8);
    std::erase_if(live, [&](std::size_t j) { return states[j].done; });
    if (live.empty()) break;
    Evaluation full;
    line_search(f, states, live, o, full);
    // Accepted points: the full step's derivatives are there; shorter steps need new ones.
    std::vector<std::size_t> again;
    for (const std::size_t j : live) {
      State& s = states[j];
      if (!s.accepted) continue;
      s.factor_current = false;
      ++s.point.iterations;
      if (s.t == 1.0) {
        const std::size_t r = row_of(live, j);
        s.point.value = s.full_value;
        if (!finite_derivatives(full, r)) {
          s.point.status = MinimizeStatus::kNonFinite;
          s.done = true;
          continue;
        }
        s.gradient = full.gradient.row(static_cast<Eigen::Index>(r)).transpose();
        s.hessian = full.hessian_at(static_cast<Eigen::Index>(r));
      } else {
        again.push_back(j);
      }
    }
    if (!again.empty()) {
      RowMatrix x(static_cast<Eigen::Index>(again.size()), x0.cols());
      for (std::size_t r = 0; r < again.size(); ++r)
        x.row(static_cast<Eigen::Index>(r)) = states[again[r]].point.x.transpose();
      f.evaluate(again, x, Derivatives::kHessian, e);
      for (std::size_t r = 0; r < again.size(); ++r) {
        State& s = states[again[r]];
        s.point.value = e.value[static_cast<Eigen::Index>(r)];
        if (!std::isfinite(s.point.value) || !finite_derivatives(e, r)) {
          s.point.status = MinimizeStatus::kNonFinite;
          s.done = true;
          continue;
        }
        s.gradient = e.gradient.row(static_cast<Eigen::Index>(r)).transpose();
        s.hessian = e.hessian_at(static_cast<Eigen::Index>(r));
      }
    }
    for (const std::size_t j : live) {
      State& s = states[j];
      if (!s.accepted || s.done) continue;
      if (s.t * s.size <= o.step_tolerance * s.x_scale ||
          (s.exact && s.t == 1.0 && s.size <= o.final_step)) {
        s.point.status = MinimizeStatus::kConverged;
        s.done = true;
      }
    }
  }
  // The factor at the final point (a particle that moved since its last factorisation).
  parallel_for(
      n,
      [&](std::size_t j) {
        State& s = states[j];
        NewtonPoint& p = s.point;
        if (p.status == MinimizeStatus::kNonFinite) {
          p.factor_ok = false;
          return;
        }
        if (!s.factor_current)
          p.factor_ok = detail::factor_with_fallback(
              p.factor, s.hessian, static_cast<MatX*>(nullptr), s.damped, s.exact, o.damping);
        if (!p.factor_ok) p.status = MinimizeStatus::kNotPositiveDefinite;
      },
      8);
  std::vector<NewtonPoint> out(n);
  for (std::size_t j = 0; j < n; ++j) out[j] = std::move(states[j].point);
  return out;
}

}  // namespace implicit::python::ssm
