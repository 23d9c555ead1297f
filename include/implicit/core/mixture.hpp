#pragma once
// Mixture proposals for targets with several minima.
//
// Given the Laplace approximations (mu_k, phi_k, L_k) of K minima, the proposal is
//   q(x) = sum_k pi_k N(x; mu_k, H_k^{-1}),   pi_k ∝ exp(-phi_k) / det L_k
// (each component weighted by its Laplace estimate of the mass near that minimum). A sample picks
// k by inverse CDF from one uniform, then x = mu_k + L_k^{-T} xi, and log w = -F(x) - log q(x).
// E[w] = Z exactly, whatever the pi_k; every component's density enters q, so overlapping modes
// are not double counted.

#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/laplace.hpp"
#include "implicit/core/target.hpp"
#include "implicit/core/weights.hpp"

namespace implicit {

template <int N>
class MixtureProposal {
 public:
  explicit MixtureProposal(std::vector<Laplace<N>> components)
      : components_(std::move(components)) {
    require(!components_.empty(), "mixture proposal: expected at least one component, got none");
    const int m = components_.front().dim();
    log_pi_.resize(components_.size());
    for (std::size_t k = 0; k < components_.size(); ++k) {
      require(components_[k].dim() == m,
              "mixture proposal: component {} has dimension {}, expected {}", k,
              components_[k].dim(), m);
      log_pi_[k] = -components_[k].phi - components_[k].log_det_L;
    }
    const double lse = log_sum_exp(log_pi_);
    cumulative_.resize(components_.size());
    double c = 0.0;
    for (std::size_t k = 0; k < components_.size(); ++k) {
      log_pi_[k] -= lse;
      c += std::exp(log_pi_[k]);
      cumulative_[k] = c;
    }
  }

  const std::vector<Laplace<N>>& components() const { return components_; }
  /// log pi_k of each component.
  const std::vector<double>& log_mixture_weights() const { return log_pi_; }

  /// Component chosen by the uniform u in (0, 1).
  std::size_t choose(double u) const {
    for (std::size_t k = 0; k + 1 < cumulative_.size(); ++k)
      if (u < cumulative_[k]) return k;
    return cumulative_.size() - 1;
  }

  /// log q(x). Streaming log-sum-exp over the components: no allocation per call.
  double log_density(const Vec<N>& x) const {
    const double m = static_cast<double>(x.size());
    double top = -std::numeric_limits<double>::infinity(), sum = 0.0;
    for (std::size_t k = 0; k < components_.size(); ++k) {
      const auto& c = components_[k];
      const Vec<N> v = c.L.transpose() * (x - c.mu);
      const double t =
          log_pi_[k] - gaussian_log_normaliser(m, 0.0) + c.log_det_L - 0.5 * v.squaredNorm();
      if (!(t > -std::numeric_limits<double>::infinity())) continue;  // zero density (or NaN x)
      if (t > top) {
        sum = sum * std::exp(top - t) + 1.0;
        top = t;
      } else {
        sum += std::exp(t - top);
      }
    }
    return sum > 0.0 ? top + std::log(sum) : -std::numeric_limits<double>::infinity();
  }

  /// Samples with component choice u and reference variable xi; returns log w.
  template <Target T, typename XiDerived>
  double sample(const T& f, double u, const Eigen::MatrixBase<XiDerived>& xi, Vec<N>& x) const {
    x = components_[choose(u)].map(xi);
    const double fx = f.evaluate(x, nullptr, nullptr);
    if (!(fx < std::numeric_limits<double>::infinity()))
      return -std::numeric_limits<double>::infinity();
    return -fx - log_density(x);
  }

 private:
  std::vector<Laplace<N>> components_;
  std::vector<double> log_pi_;
  std::vector<double> cumulative_;
};

}  // namespace implicit
