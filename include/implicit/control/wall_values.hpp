#pragma once
// Sampling only the wall values, for linear-quadratic problems (a model that declares
// `static constexpr bool kLinearQuadratic = true`: affine drift, quadratic running and final
// costs). F is then quadratic with a constant Hessian H, so at a mode's minimum mu with gradient
// g = A nu (A: one column per wall ahead, the wall's direction at its block),
//
//   F(mu + L^{-T} xi) = phi + nu . delta + |xi|^2 / 2,   delta = A^T L^{-T} xi ~ N(0, A^T H^-1 A),
//
// and a sample passes the walls when a_i^T mu + delta_i lies in the mode's openings. A sample's
// weight and its wall tests depend on delta alone: drawing delta (one normal per wall) instead
// of xi (one per path entry) gives the same estimator at a fraction of the cost (spec §2.4.4's
// wall-space form of W, for any linear-quadratic problem and any number of walls).

#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/control/wall_mixture.hpp"
#include "implicit/control/wall_modes.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// True if Model declares `static constexpr bool kLinearQuadratic = true`.
template <typename Model>
constexpr bool declares_linear_quadratic() {
  if constexpr (requires { Model::kLinearQuadratic; })
    return static_cast<bool>(Model::kLinearQuadratic);
  else
    return false;
}

namespace detail {

/// Checks a model's kLinearQuadratic declaration at one point y = mu + d off the minimum: a
/// quadratic F has F(y) = phi + g . d + d^T H d / 2 there. Throws InvalidArgument otherwise.
template <typename PathF>
void require_quadratic(const PathF& F, const Eigen::VectorXd& mu, double phi,
                       const Eigen::VectorXd& g, const Eigen::VectorXd& d, double dHd) {
  const double predicted = phi + g.dot(d) + 0.5 * dHd;
  const double actual = F.evaluate(mu + d, nullptr, nullptr);
  require(std::abs(actual - predicted) <= 1e-7 * (1.0 + std::abs(phi) + std::abs(predicted)),
          "path integral estimator: the model declares kLinearQuadratic, but its path function "
          "is not quadratic (F = {} where a quadratic F gives {}); remove the declaration or make "
          "the drift affine and the costs quadratic",
          actual, predicted);
}

/// One mode's wall-value sampler: delta = chol_s eta (eta ~ N(0, I_A)), the weight's slope nu
/// and the wall values a_i^T mu at the minimum.
struct WallValueSampler {
  Eigen::MatrixXd chol_s;  ///< lower Cholesky factor of S = A^T H^-1 A
  Eigen::VectorXd nu;      ///< grad F(mu) = A nu
  Eigen::VectorXd at_mu;   ///< a_i^T mu
};

/// Builds the sampler of a mode with minimiser mu, F(mu) = phi, gradient g and the exact factor
/// of H. Returns false when g is not in the span of A (the minimiser stopped short), when S is
/// not positive definite, or when the factor is not H's own (damped): the caller then samples
/// whole paths. Throws InvalidArgument when F is not quadratic although the model says so.
template <typename PathF, typename Problem>
bool make_wall_value_sampler(const PathF& F, const WallsAhead<Problem>& w,
                             const Eigen::VectorXd& mu, double phi, const Eigen::VectorXd& g,
                             const BandedFactor<PathF::Block>& factor, bool exact_factor,
                             WallValueSampler& out) {
  constexpr int D = PathF::Block;
  const int A = w.size();
  const Eigen::Index N = mu.size();
  if (!exact_factor || g.size() != N) return false;
  Eigen::MatrixXd cols = Eigen::MatrixXd::Zero(N, A);
  for (int i = 0; i < A; ++i)
    cols.col(i).template segment<D>(w.block_of(i) * D) = w.wall(i).direction;
  Eigen::MatrixXd z = cols;  // H^-1 A, column by column through the banded factor
  for (int i = 0; i < A; ++i) {
    Eigen::VectorXd c = z.col(i);
    factor.solve_in_place(c);
    z.col(i) = c;
  }
  const Eigen::MatrixXd s = cols.transpose() * z;
  const Eigen::LLT<Eigen::MatrixXd> llt(s);
  if (llt.info() != Eigen::Success) return false;
  out.nu = (cols.transpose() * cols).ldlt().solve(cols.transpose() * g);
  const double scale = 1.0 + g.cwiseAbs().maxCoeff();
  if ((g - cols * out.nu).cwiseAbs().maxCoeff() > 1e-7 * scale) return false;
  require_quadratic(F, mu, phi, g, z.col(0), s(0, 0));  // at y = mu + H^-1 a_0
  out.chol_s = llt.matrixL();
  out.at_mu.resize(A);
  for (int i = 0; i < A; ++i) out.at_mu(i) = w.value(i, mu);
  return true;
}

/// Stratified sampling of the wall values (ModeSampling::kEachMode or kDominant, the linear map):
/// M samples of delta per mode in `used` from `refs` (A normals each), log weights (without the
/// path normaliser) appended to `lw`: -inf outside the mode's openings; `laplace` drops the
/// nu . delta term (the paper's estimator P). Returns false, drawing nothing, if some mode has no
/// wall-value sampler (make_wall_value_sampler): the caller samples whole paths instead.
template <typename PathF, typename Problem>
bool sample_wall_values(const PathF& F, const WallsAhead<Problem>& w,
                        WallMixture<PathF::Block>& mix, const std::vector<std::size_t>& used, int M,
                        ReplayableNormals& refs, bool laplace, std::vector<double>& lw) {
  std::vector<WallValueSampler> samplers(used.size());
  for (std::size_t u = 0; u < used.size(); ++u) {
    const std::size_t c = used[u];
    const WallMode& md = mix.modes[c];
    if (!make_wall_value_sampler(F, w, md.minimizer, md.phi, mix.gradients[c], mix.factors[c],
                                 mix.exact[c] != 0, samplers[u]))
      return false;
  }
  const int N = static_cast<int>(mix.modes[used.front()].minimizer.size());
  const int A = w.size();
  Eigen::VectorXd eta(static_cast<Eigen::Index>(A) * M);
  std::vector<double> lower(static_cast<std::size_t>(A)), upper(lower);
  const std::size_t first = lw.size();
  lw.resize(first + used.size() * static_cast<std::size_t>(M));
  for (std::size_t u = 0; u < used.size(); ++u) {
    WallMode& md = mix.modes[used[u]];
    const WallValueSampler& s = samplers[u];
    // A sample passes when a_i^T mu + delta_i is inside the mode's opening at every wall i.
    for (int i = 0; i < A; ++i) {
      lower[static_cast<std::size_t>(i)] = w.opening(i, md).lower - s.at_mu(i);
      upper[static_cast<std::size_t>(i)] = w.opening(i, md).upper - s.at_mu(i);
    }
    refs.next(eta);  // the mode's M draws of A normals at once: the same numbers, less overhead
    for (int j = 0; j < M; ++j) {
      // delta = chol_s eta_j and the weight's exponent nu . delta by hand: A is a handful, where
      // Eigen's general products cost more than the arithmetic.
      bool inside = true;
      double slope = 0.0;
      for (int i = 0; i < A; ++i) {
        double d = 0.0;
        for (int k = 0; k <= i; ++k) d += s.chol_s(i, k) * eta(j * A + k);
        inside = inside && d > lower[static_cast<std::size_t>(i)] &&
                 d < upper[static_cast<std::size_t>(i)];
        slope += s.nu(i) * d;
      }
      // F(y) - |xi|^2 / 2 = phi + nu . delta: the kernel's weight with |xi|^2 / 2 cancelled.
      lw[first + u * static_cast<std::size_t>(M) + static_cast<std::size_t>(j)] =
          inside
              ? implicit_log_weight(N, 0.0, md.phi + (laplace ? 0.0 : slope), mix.log_det[used[u]])
              : -std::numeric_limits<double>::infinity();
      if (!inside) ++md.wall_hits;
    }
    md.samples += M;
  }
  return true;
}

}  // namespace detail
}  // namespace implicit::control
