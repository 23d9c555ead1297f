#pragma once
// Path integral control on the implicit-sampling kernel: the banded path function F is an
// objective of core's newton_minimize (factor model BandedFactor<D>, so every step stays O(n)),
// with linear equality constraints when a path is held at a wall's edge, and its random map
// solves the ray equation with core's solve_random_map_ray. What stays here is what belongs to
// paths: the wall constraints, F along a ray in one O(n) pass, and F restricted to one mode's
// openings.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control::detail {

/// The minimum of a path function: minimiser, F, Hessian factor (Levenberg-damped when the
/// Hessian is not SPD: the proposal is then not the Laplace approximation, but the weights stay
/// exact) and, with constraints, the multipliers nu (grad F + C nu = 0).
template <int D>
using PathMinimum = NewtonMinimum<BandedFactor<D>>;

/// C^T y = e over a path: one column of C per constraint (a wall's direction at one block).
using PathConstraints = EqualityConstraints<Eigen::Dynamic>;

/// |L^T v|^2 for a banded factor, without allocation.
template <int B>
double upper_norm2(const BlockTridiagonalCholesky<B>& f, const Eigen::VectorXd& v) {
  const int n = f.num_blocks();
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    Vec<B> r = f.diagonal_block(i).transpose() * v.template segment<B>(i * B);
    if (i + 1 < n)
      r.noalias() += f.subdiagonal_block(i).transpose() * v.template segment<B>((i + 1) * B);
    s += r.squaredNorm();
  }
  return s;
}

/// Sizes `c` for `count` constraints on paths of `size` entries, all zero.
inline void reset_constraints(PathConstraints& c, Eigen::Index size, int count) {
  c.C.setZero(size, count);
  c.e.setZero(count);
}

/// Constraint j: a^T y_block = value (block is 0-based).
template <int D>
void set_constraint(PathConstraints& c, int j, int block, const Vec<D>& a, double value) {
  c.C.col(j).template segment<D>(block * D) = a;
  c.e(j) = value;
}

/// min F(y) subject to `constraints` (none: unconstrained) from x0, by the kernel's damped
/// Newton with the path function's factor model (banded with noise on every coordinate, dense
/// with partial noise; range-space steps with constraints).
template <typename PathF>
NewtonMinimum<typename PathF::Factor> minimize_path(const PathF& f, const Eigen::VectorXd& x0,
                                                    const MinimizeOptions& options,
                                                    const PathConstraints* constraints = nullptr) {
  return newton_minimize<typename PathF::Factor>(f, x0, NewtonOptions(options), constraints);
}

/// F along a ray, +inf where `inside(lambda)` is false (one mode's openings).
template <typename PathF, typename Inside>
struct RestrictedPath {
  const PathF& f;
  Inside inside;
  double evaluate_along(const Eigen::VectorXd& base, const Eigen::VectorXd& dir, double lambda,
                        double* slope) const {
    if (!inside(lambda)) {
      if (slope) *slope = 0.0;
      return std::numeric_limits<double>::infinity();
    }
    return f.evaluate_along(base, dir, lambda, slope);
  }
};
// Written out because clang before 17 does not deduce aggregate template arguments.
template <typename PathF, typename Inside>
RestrictedPath(const PathF&, Inside) -> RestrictedPath<PathF, Inside>;

/// The random map's scalar equation F(mu + lambda d) = level along one ray (spec §1.3), solved
/// by the kernel's root finder with F evaluated along the ray in one O(n) pass
/// (`evaluate_along`). kJump: F jumps to +inf (a wall) before reaching the level, so the sample
/// has weight exactly zero.
template <typename PathF>
RayStatus solve_path_ray(const PathF& f, const Eigen::VectorXd& mu, const Eigen::VectorXd& d,
                         double level, double rho, double& lambda, double& slope) {
  auto g_of = [&](double l, double* s) {
    const double fl = f.evaluate_along(mu, d, l, s);
    return std::isnan(fl) ? std::numeric_limits<double>::infinity() : fl - level;
  };
  return solve_random_map_ray(g_of, rho, level, lambda, slope);
}

}  // namespace implicit::control::detail
