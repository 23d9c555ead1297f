#pragma once
// A state-space model defined in Python (implicit.ssm): the pieces shared by the filter driver
// (user_model.cpp) and the implicit proposal run for all particles in lockstep
// (user_model_newton.cpp) and the random map (user_model_random_map.cpp).
//
// The Python callbacks work on all particles at once (arrays of shape (k, d)), so the implicit
// proposal cannot run core's newton_minimize() particle by particle: its objective is a
// synchronous call per point, and one Python call per particle and iteration is what this layer
// exists to avoid. lockstep_newton() runs the same damped Newton for every particle at once, one
// batched evaluation per iteration (and per backtracking round); what decides a step is core's:
// the factor (DenseFactor), its fallback (detail::factor_with_fallback: exact, then Levenberg),
// the stopping rules of NewtonOptions, and the weight (implicit_log_weight). docs/design.md
// ("Your own model in Python") argues the choice.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"

namespace implicit::python::ssm {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using VecX = Vec<Eigen::Dynamic>;
using MatX = Mat<Eigen::Dynamic>;
using Factor = DenseFactor<Eigen::Dynamic>;

/// F at k points: value (k), and with derivatives gradient (k, d) and the Hessians (k, d * d),
/// row r holding point r's row by row (one allocation per call, not one per point).
struct Evaluation {
  VecX value;
  RowMatrix gradient;
  RowMatrix hessian;

  Eigen::Map<RowMatrix> hessian_at(Eigen::Index r) {
    return {hessian.row(r).data(), gradient.cols(), gradient.cols()};
  }
  Eigen::Map<const RowMatrix> hessian_at(Eigen::Index r) const {
    return {hessian.row(r).data(), gradient.cols(), gradient.cols()};
  }
};

/// What an evaluation computes: F; F and its gradient (the random map's slope); all three.
enum class Derivatives { kNone, kGradient, kHessian };

/// F(x) = -log p(y | x) - log p(x | x') for many points at once; row r of `x` is a point of
/// particle owner[r]. Values may be +inf (outside the support); derivatives are read only where
/// the value is finite.
class BatchObjective {
 public:
  virtual ~BatchObjective() = default;
  virtual void evaluate(const std::vector<std::size_t>& owner, const RowMatrix& x,
                        Derivatives derivatives, Evaluation& out) = 0;
};

/// One particle's minimisation: the centre mu, phi = F(mu), the factor of the Hessian used there.
struct NewtonPoint {
  VecX x;
  double value = 0.0;
  Factor factor;
  bool factor_ok = false;  ///< false: no SPD factor at x (the particle gets weight zero)
  int iterations = 0;
  MinimizeStatus status = MinimizeStatus::kMaxIterations;
};

/// Damped Newton from every row of x0 at once (see the file comment); parallel over particles
/// between the batched evaluations.
std::vector<NewtonPoint> lockstep_newton(BatchObjective& f, const RowMatrix& x0,
                                         const NewtonOptions& options);

/// The random map's samples (a failed ray: the centre) and log weights (-inf on failure).
struct MapResult {
  RowMatrix x;
  VecX log_weight;
  int failures = 0;  ///< rays without a root (RayStatus other than kOk): weight zero
};

/// The random map x = mu + lambda L^-T xi / |xi| for every particle at once, one batched call
/// of F per round of the root finder (user_model_random_map.cpp); particles without an SPD
/// factor get weight zero.
MapResult lockstep_random_map(BatchObjective& f, const std::vector<NewtonPoint>& points,
                              const RowMatrix& xi, const RandomMapOptions& options);

}  // namespace implicit::python::ssm
