#pragma once
// The linear map of implicit sampling (quadratic approximation of F at its minimum), for a dense
// target and its Laplace approximation.
//
//   X = mu + L^{-T} xi,  xi ~ N(0, I_m),  H = L L^T
//   log w = (m/2) log 2pi - log det L + |xi|^2/2 - F(X)
//         = (m/2) log 2pi - log det L - phi + [F_hat(X) - F(X)]
//
// With these constants E[w] = Z = integral of exp(-F) exactly, so the mean weight estimates the
// normalising constant. For a Gaussian target all weights are equal. Caution: if the target's
// tails are heavier than the Gaussian's (Gamma, logistic), Var(w) is infinite: use the random map.
// Samples with F(X) = +inf get log w = -inf (weight 0); a NaN F also gives -inf and is counted as
// non-finite by the sample-set drivers. linear_map_sample() is the kernel's linear_map
// (implicit_maps.hpp, weighed by implicit_log_weight) with the factor L of the Laplace
// approximation.

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/laplace.hpp"
#include "implicit/core/target.hpp"

namespace implicit {

/// Maps xi to x (written to `x`) and returns log w, including every constant.
template <Target T, typename XiDerived>
double linear_map_sample(const T& f, const Laplace<T::Dim>& lp,
                         const Eigen::MatrixBase<XiDerived>& xi, typename T::Vector& x) {
  return linear_map(f, lp.mu, lp.factor(), xi, x);
}

}  // namespace implicit
