#pragma once
// The Gaussian (Laplace) approximation at a minimum: centre mu, phi = F(mu), H = L L^T.
//
// Both maps of implicit sampling are built on (mu, phi, L). The weights stay exact for ANY centre
// and ANY symmetric positive definite H, as long as the same (mu, L) are used for sampling and for
// the weight; so when the exact Hessian at the minimum is not SPD one may pass any SPD
// approximation (Gauss-Newton, H + eps I).

#include <cmath>
#include <optional>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

template <int N>
struct Laplace {
  Vec<N> mu;               ///< centre (the minimiser of F)
  double phi = 0.0;        ///< F(mu)
  Mat<N> L;                ///< lower Cholesky factor of the Hessian H = L L^T
  double log_det_L = 0.0;  ///< sum_i log L_ii = 1/2 log det H

  int dim() const { return static_cast<int>(mu.size()); }

  /// Builds from a centre, value and SPD Hessian; std::nullopt if H is not positive definite.
  static std::optional<Laplace> try_make(const Vec<N>& mu, double phi, const Mat<N>& hessian) {
    DenseFactor<N> llt;
    if (!llt.compute(hessian)) return std::nullopt;  // not SPD, not finite, or det H = 0
    Laplace lp;
    lp.mu = mu;
    lp.phi = phi;
    lp.L = llt.matrixL();
    lp.log_det_L = llt.log_det_L();
    return lp;
  }

  /// L as the kernel's factor (implicit_maps.hpp); refers to this approximation's L.
  LowerFactorView<N> factor() const { return LowerFactorView<N>(L, log_det_L); }

  /// As try_make, but throws InvalidArgument naming the problem.
  static Laplace make(const Vec<N>& mu, double phi, const Mat<N>& hessian) {
    require(mu.size() == hessian.rows() && hessian.rows() == hessian.cols(),
            "Laplace approximation: expected a {}x{} Hessian, got {}x{}", mu.size(), mu.size(),
            hessian.rows(), hessian.cols());
    require(std::isfinite(phi), "Laplace approximation: expected a finite F(mu), got {}", phi);
    auto lp = try_make(mu, phi, hessian);
    require(lp.has_value(),
            "Laplace approximation: expected a symmetric positive definite Hessian at the minimum, "
            "but its Cholesky factorisation failed (use a Gauss-Newton or damped Hessian)");
    return *lp;
  }

  /// From a minimiser result; throws if the minimiser did not converge to an SPD point.
  static Laplace from(const MinimizeResult<N>& r) {
    require(r.status == MinimizeStatus::kConverged ||
                r.status == MinimizeStatus::kNotPositiveDefinite ||
                r.status == MinimizeStatus::kMaxIterations,
            "Laplace approximation: the minimiser failed with status '{}'", to_string(r.status));
    return make(r.x, r.value, r.hessian);
  }

  /// x = mu + L^{-T} xi (back substitution; H^{-1} is never formed).
  template <typename XiDerived>
  Vec<N> map(const Eigen::MatrixBase<XiDerived>& xi) const {
    return mu + L.transpose().template triangularView<Eigen::Upper>().solve(xi);
  }
};

}  // namespace implicit
