#pragma once
// Hard walls and the modes they create (spec §2.4.3): with walls ahead of step k, a path must
// pass one opening per wall, so psi is a sum over combinations of openings. Each combination is
// a mode: the minimum of F constrained to its openings, found by an active set over the wall
// constraints. The estimators (estimators.hpp) sample a Gaussian mixture over the modes.

#include <algorithm>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "implicit/control/path_solvers.hpp"
#include "implicit/control/problem.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// One combination of openings (one per wall ahead) and its constrained minimum: a component of
/// the mixture proposal.
struct WallMode {
  std::vector<int> walls;     ///< the walls ahead (indices into problem.walls())
  std::vector<int> openings;  ///< the opening chosen at each wall ahead
  std::vector<int> clamped;   ///< per wall ahead: 0 free, -1 held at the lower, +1 the upper edge
  std::vector<double> wall_values;  ///< a^T mu at each wall ahead (the frozen values for x +- h)
  double log_weight = -std::numeric_limits<double>::infinity();  ///< log pi (mixture weight)
  double phi = std::numeric_limits<double>::infinity();          ///< F at the constrained minimum
  int samples = 0;    ///< samples drawn from this component
  int wall_hits = 0;  ///< of those, samples that hit a wall
  MinimizeStatus status = MinimizeStatus::kConverged;
  Eigen::VectorXd minimizer;
};

namespace detail {

/// The walls still ahead of grid step k and where they cut the path y_1..y_n: wall i ahead
/// tests a_i^T y at block block_of(i) (0-based).
template <typename Problem>
struct WallsAhead {
  static constexpr int D = Problem::kStateDim;
  const Problem& problem;
  int k = 0;
  std::vector<int> ahead;   ///< indices into problem.walls()
  std::vector<int> blocks;  ///< the path block of each wall ahead (looked up once: hot)

  WallsAhead(const Problem& p, int step) : problem(p), k(step) {
    for (std::size_t j = 0; j < p.walls().size(); ++j) {
      if (p.wall_step(j) <= k) continue;
      ahead.push_back(static_cast<int>(j));
      blocks.push_back(p.block_at_step(k, p.wall_step(j)));
    }
  }
  int size() const { return static_cast<int>(ahead.size()); }
  const auto& wall(int i) const {
    return problem.walls()[static_cast<std::size_t>(ahead[static_cast<std::size_t>(i)])];
  }
  /// The opening mode `md` chose at wall i ahead.
  const WallOpening& opening(int i, const WallMode& md) const {
    return wall(i).openings[static_cast<std::size_t>(md.openings[static_cast<std::size_t>(i)])];
  }
  int block_of(int i) const { return blocks[static_cast<std::size_t>(i)]; }
  double value(int i, const Eigen::VectorXd& v) const {
    return wall(i).direction.dot(v.template segment<D>(block_of(i) * D));
  }
  /// True if the path y passes every wall ahead (through any opening).
  bool passes(const Eigen::VectorXd& y) const {
    for (int i = 0; i < size(); ++i)
      if (!wall(i).passes(y.template segment<D>(block_of(i) * D))) return false;
    return true;
  }
};

/// One mode per combination of openings of the walls ahead (at most 256), all walls free.
template <typename Problem>
std::vector<WallMode> enumerate_modes(const WallsAhead<Problem>& w) {
  const int A = w.size();
  std::size_t count = 1;
  for (int i = 0; i < A; ++i) {
    count *= w.wall(i).openings.size();
    require(count <= 256,
            "path integral estimator: expected at most 256 combinations of wall openings, got "
            "more than {}",
            count / w.wall(i).openings.size());
  }
  std::vector<WallMode> modes(count);
  for (std::size_t c = 0; c < count; ++c) {
    modes[c].walls = w.ahead;
    modes[c].openings.resize(static_cast<std::size_t>(A));
    std::size_t rest = c;
    for (int i = A - 1; i >= 0; --i) {
      const std::size_t no = w.wall(i).openings.size();
      modes[c].openings[static_cast<std::size_t>(i)] = static_cast<int>(rest % no);
      rest /= no;
    }
    modes[c].clamped.assign(static_cast<std::size_t>(A), 0);
  }
  return modes;
}

/// Active set for mode `md` from `from`: minimise with the clamped walls held at their edges;
/// clamp every wall whose value leaves its opening (to the nearest edge), release clamped walls
/// whose multiplier pulls back into the opening, repeat. For a convex F and one wall the first
/// clamp is already exact (the minimum over a convex set lies on the boundary when the free
/// minimiser is outside it); with several walls or a non-convex F this is a safeguarded
/// heuristic, capped at 2 A + 2 rounds. `clamped` is updated in place.
template <typename PathF, typename Problem>
PathMinimum<PathF::Block> active_set_search(const PathF& F, const WallsAhead<Problem>& w,
                                            const WallMode& md, const Eigen::VectorXd& from,
                                            std::vector<int>& clamped,
                                            const MinimizeOptions& options, PathConstraints& cons) {
  const int A = w.size();
  PathMinimum<PathF::Block> r;
  Eigen::VectorXd at = from;
  for (int round = 0; round < 2 * A + 2; ++round) {
    const auto held = std::count_if(clamped.begin(), clamped.end(), [](int s) { return s != 0; });
    reset_constraints(cons, from.size(), static_cast<int>(held));
    for (int i = 0, j = 0; i < A; ++i) {
      const int side = clamped[static_cast<std::size_t>(i)];
      if (side == 0) continue;
      const auto& op = w.opening(i, md);
      set_constraint(cons, j++, w.block_of(i), w.wall(i).direction, side < 0 ? op.lower : op.upper);
    }
    r = minimize_path(F, at, options, &cons);
    if (r.status == MinimizeStatus::kNonFinite) break;
    at = r.x;
    bool changed = false;
    for (int i = 0; i < A; ++i) {
      if (clamped[static_cast<std::size_t>(i)] != 0) continue;
      const auto& op = w.opening(i, md);
      const double v = w.value(i, at);
      if (v <= op.lower || v >= op.upper) {
        clamped[static_cast<std::size_t>(i)] = v <= op.lower ? -1 : 1;
        changed = true;
      }
    }
    if (!changed) {
      // KKT: held at the upper edge needs nu >= 0, at the lower edge nu <= 0.
      int j = 0;
      for (int i = 0; i < A; ++i) {
        int& side = clamped[static_cast<std::size_t>(i)];
        if (side == 0) continue;
        if (side * r.multipliers(j) < 0.0) {
          side = 0;
          changed = true;
        }
        ++j;
      }
    }
    if (!changed) break;
  }
  return r;
}

/// The free minimiser translated along each wall's direction so that it passes through the
/// mode's openings: the shift ramps up linearly from the previous wall and is kept after the
/// wall. For a non-convex F (an obstacle to pass on either side) clamping only the wall point
/// can leave the rest of the path on the wrong side, a poor local minimum; this second start
/// avoids that.
template <typename Problem>
Eigen::VectorXd shifted_start(const WallsAhead<Problem>& w, const WallMode& md,
                              const Eigen::VectorXd& free_min) {
  constexpr int D = Problem::kStateDim;
  const int A = w.size();
  const int n = static_cast<int>(free_min.size()) / D;
  Eigen::VectorXd shifted = free_min;
  std::vector<int> order(static_cast<std::size_t>(A));
  for (int i = 0; i < A; ++i) order[static_cast<std::size_t>(i)] = i;
  std::sort(order.begin(), order.end(),
            [&](int p, int q) { return w.block_of(p) < w.block_of(q); });
  int previous = -1;
  for (int i : order) {
    const auto& wall = w.wall(i);
    const auto& op = w.opening(i, md);
    const double v = w.value(i, shifted);
    const double target = std::clamp(v, op.lower, op.upper);
    const int b_wall = w.block_of(i);
    if (target != v && b_wall > previous) {
      const Vec<D> delta = (target - v) / wall.direction.squaredNorm() * wall.direction;
      for (int b = previous + 1; b < n; ++b)
        shifted.template segment<D>(b * D) +=
            std::min(1.0, static_cast<double>(b - previous) / (b_wall - previous)) * delta;
    }
    previous = std::max(previous, b_wall);
  }
  return shifted;
}

/// The constrained minimum of mode `md`. Frozen: the wall values are held at md.wall_values
/// from md.minimizer. Otherwise the active set from two starts, the free minimiser and its
/// shifted copy (shifted_start); the lower constrained F wins; a `convex` F needs only the
/// first. Updates md.clamped. An inexact centre costs efficiency only: the weights use the true
/// F, so the estimator stays unbiased for any centre.
template <typename PathF, typename Problem>
PathMinimum<PathF::Block> mode_minimum(const PathF& F, const WallsAhead<Problem>& w, WallMode& md,
                                       const Eigen::VectorXd& free_min, bool frozen,
                                       const MinimizeOptions& options, PathConstraints& cons,
                                       bool convex = false) {
  const int A = w.size();
  if (frozen) {
    reset_constraints(cons, md.minimizer.size(), A);
    for (int i = 0; i < A; ++i)
      set_constraint(cons, i, w.block_of(i), w.wall(i).direction,
                     md.wall_values[static_cast<std::size_t>(i)]);
    return minimize_path(F, md.minimizer, options, &cons);
  }
  std::vector<int> clamped_free = md.clamped, clamped_start = md.clamped;
  auto r = active_set_search(F, w, md, free_min, clamped_free, options, cons);
  md.clamped = clamped_free;
  if (convex) return r;
  const Eigen::VectorXd shifted = shifted_start(w, md, free_min);
  if ((shifted - free_min).cwiseAbs().maxCoeff() > 0.0) {
    auto other = active_set_search(F, w, md, shifted, clamped_start, options, cons);
    const bool other_ok = other.status != MinimizeStatus::kNonFinite && other.factor_ok;
    const bool r_ok = r.status != MinimizeStatus::kNonFinite && r.factor_ok;
    if (other_ok && (!r_ok || other.value < r.value)) {
      r = std::move(other);
      md.clamped = clamped_start;
    }
  }
  return r;
}

}  // namespace detail
}  // namespace implicit::control
