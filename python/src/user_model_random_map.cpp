// The random map of implicit sampling for all particles in lockstep: core's
// solve_random_map_ray() (core/implicit_maps.hpp) as a state machine per particle, so that the
// points of one round (one per unfinished ray) are evaluated in one batched call of F.
//
// The rules are solve_random_map_ray()'s: bracket [0, hi] with hi doubled from sqrt(rho) until
// g > 0, Newton steps safeguarded by bisection from the quadratic model's root, the jump-at-zero
// and jump-to-+inf verdicts, and the final residual and slope checks; the weight is core's
// implicit_log_weight with random_map_log_jacobian. Core's loop calls g synchronously, so it
// cannot wait for a batch; this is the same loop with each evaluation a resumption point.

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/log_weight.hpp"
#include "user_model.hpp"

namespace implicit::python::ssm {
namespace {

/// One particle's ray, between evaluations of g(lambda) = F(mu + lambda d) - level.
struct Ray {
  enum class Phase { kBracket, kNewton, kFinal, kJumpCheck, kDone };
  VecX d;
  double rho = 0.0, level = 0.0, lo = 0.0, hi = 0.0, lambda = 0.0, jump_at_zero = 0.0;
  double slope = 0.0;  ///< g'(lambda) at the root
  bool only_infinite = false, first = true, converged = false;
  int doublings = 0, iterations = 0;
  Phase phase = Phase::kBracket;
  RayStatus status = RayStatus::kNotConverged;

  double at() const { return phase == Phase::kBracket || phase == Phase::kJumpCheck ? hi : lambda; }
  bool wants_slope() const { return phase == Phase::kNewton || phase == Phase::kFinal; }
  void end(RayStatus s) {
    status = s;
    phase = Phase::kDone;
  }

  /// Takes g (and g') at at() and decides what to evaluate next.
  void answer(double g, double g_slope, const RandomMapOptions& o) {
    const double mid = 0.5 * (lo + hi);
    switch (phase) {
      case Phase::kBracket:
        if (first) only_infinite = std::isinf(g);
        first = false;
        if (!(g > 0.0)) {  // an infinite or NaN F also ends the bracket
          if (++doublings > o.max_doublings) return end(RayStatus::kBracketFailed);
          lo = hi;
          hi *= 2.0;
          return;
        }
        lambda = std::min(std::sqrt(rho), mid);
        if (lambda <= lo) lambda = mid;
        phase = Phase::kNewton;
        return;
      case Phase::kNewton: {
        if (g > 0.0)
          hi = lambda;
        else
          lo = lambda;
        only_infinite = only_infinite && std::isinf(g);
        if (only_infinite && lo == 0.0 && hi <= jump_at_zero) return end(RayStatus::kJump);
        const double bisect = 0.5 * (lo + hi);
        double next = std::isfinite(g) && g_slope > 0.0 ? lambda - g / g_slope : bisect;
        if (!(next > lo && next < hi)) next = bisect;
        const double change = std::abs(next - lambda);
        lambda = next;
        converged = change <= o.relative_tolerance * lambda || hi - lo <= o.relative_tolerance * hi;
        if (converged || ++iterations >= o.max_iterations) phase = Phase::kFinal;
        return;
      }
      case Phase::kFinal:
        if (!std::isfinite(g) || std::abs(g) > 1e-6 * (1.0 + std::abs(level))) {
          if (!converged) return end(RayStatus::kNotConverged);
          phase = Phase::kJumpCheck;  // converged onto a jump, or not a root at all?
          return;
        }
        if (!converged) return end(RayStatus::kNotConverged);
        slope = g_slope;
        if (!(std::abs(slope) > 0.0) || !std::isfinite(slope))
          return end(RayStatus::kZeroDerivative);
        return end(RayStatus::kOk);
      case Phase::kJumpCheck:
        return end(std::isfinite(g) ? RayStatus::kNotConverged : RayStatus::kJump);
      case Phase::kDone:
        return;
    }
  }
};

/// Evaluates g (and its slope when `slope`) for the rays of `which` in one call.
void evaluate_rays(BatchObjective& f, const std::vector<NewtonPoint>& points,
                   std::vector<Ray>& rays, const std::vector<std::size_t>& which, bool slope,
                   const RandomMapOptions& o) {
  if (which.empty()) return;
  const Eigen::Index dim = points.front().x.size();
  RowMatrix x(static_cast<Eigen::Index>(which.size()), dim);
  for (std::size_t r = 0; r < which.size(); ++r) {
    const Ray& ray = rays[which[r]];
    x.row(static_cast<Eigen::Index>(r)) = (points[which[r]].x + ray.at() * ray.d).transpose();
  }
  Evaluation e;
  f.evaluate(which, x, slope ? Derivatives::kGradient : Derivatives::kNone, e);
  for (std::size_t r = 0; r < which.size(); ++r) {
    Ray& ray = rays[which[r]];
    const auto row = static_cast<Eigen::Index>(r);
    const double fx = e.value[row];
    const double g = std::isnan(fx) ? std::numeric_limits<double>::infinity() : fx - ray.level;
    const double s = slope && std::isfinite(fx) ? e.gradient.row(row).dot(ray.d.transpose())
                                                : std::numeric_limits<double>::quiet_NaN();
    ray.answer(g, s, o);
  }
}

}  // namespace

MapResult lockstep_random_map(BatchObjective& f, const std::vector<NewtonPoint>& points,
                              const RowMatrix& xi, const RandomMapOptions& o) {
  const std::size_t n = points.size();
  const Eigen::Index dim = xi.cols();
  std::vector<Ray> rays(n);
  MapResult out;
  out.x.resize(static_cast<Eigen::Index>(n), dim);
  out.log_weight.setConstant(static_cast<Eigen::Index>(n),
                             -std::numeric_limits<double>::infinity());
  for (std::size_t j = 0; j < n; ++j) {
    Ray& ray = rays[j];
    const NewtonPoint& p = points[j];
    ray.rho = xi.row(static_cast<Eigen::Index>(j)).squaredNorm();
    if (!p.factor_ok || !(ray.rho > 1e-300)) {  // xi = 0 has probability zero: the mode, w = 0
      ray.end(p.factor_ok ? RayStatus::kZeroDerivative : RayStatus::kNotConverged);
      continue;
    }
    ray.d = xi.row(static_cast<Eigen::Index>(j)).transpose() / std::sqrt(ray.rho);
    p.factor.upper_solve_in_place(ray.d);
    ray.level = p.value + 0.5 * ray.rho;
    ray.hi = std::sqrt(ray.rho);
    ray.jump_at_zero = o.relative_tolerance * ray.hi;
  }
  for (;;) {
    std::vector<std::size_t> values, slopes;
    for (std::size_t j = 0; j < n; ++j) {
      if (rays[j].phase == Ray::Phase::kDone) continue;
      (rays[j].wants_slope() ? slopes : values).push_back(j);
    }
    if (values.empty() && slopes.empty()) break;
    evaluate_rays(f, points, rays, values, false, o);
    evaluate_rays(f, points, rays, slopes, true, o);
  }
  for (std::size_t j = 0; j < n; ++j) {
    const Ray& ray = rays[j];
    const NewtonPoint& p = points[j];
    const auto row = static_cast<Eigen::Index>(j);
    if (ray.status != RayStatus::kOk) {
      out.x.row(row) = p.x.transpose();
      ++out.failures;
      continue;
    }
    out.x.row(row) = (p.x + ray.lambda * ray.d).transpose();
    out.log_weight[row] = implicit_log_weight(
        static_cast<int>(dim), ray.rho, ray.level, p.factor.log_det_L(),
        random_map_log_jacobian(static_cast<int>(dim), ray.rho, ray.lambda, ray.slope));
  }
  return out;
}

}  // namespace implicit::python::ssm
