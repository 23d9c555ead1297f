#pragma once
// The path function of a control problem: F(y_1..y_n) over the forward-Euler path from (x, t_k),
// whose integral of exp(-F) gives psi (spec §2.2). Banded: each term couples two neighbouring
// states, so the Hessian is block tridiagonal with D x D blocks and every Newton step is O(n).
// Derivatives come from automatic differentiation of the model's drift and costs per term.

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "implicit/core/banded.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// F over y_1..y_n (n = K - k) from y_0 = x at t_k for the problem `Problem` (a ControlProblem,
/// which grants access to its model, Sigma^-1 and time grid): a banded target with D x D blocks.
template <int D, typename Problem>
class PathFunction {
 public:
  static constexpr int Block = D;
  PathFunction(const Problem* p, const Vec<D>& x, int k) : p_(p), x_(x), k_(k) {}
  int num_blocks() const { return p_->num_steps_ - k_; }
  const Vec<D>& start() const { return x_; }

  double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* grad,
                  BlockTridiagonal<D>* hess) const {
    const int n = num_blocks();
    if (grad) grad->setZero(n * D);
    if (hess) hess->resize(n);
    double f = initial_term();
    for (int i = 1; i <= n; ++i) {
      auto single = [&](const auto& yi) { return single_term(i, yi); };
      auto pair = [&](const auto& z) {
        return pair_term(i, Eigen::Matrix<std::decay_t<decltype(z(0))>, D, 1>(z.template head<D>()),
                         Eigen::Matrix<std::decay_t<decltype(z(0))>, D, 1>(z.template tail<D>()));
      };
      const Vec<D> yi = y.template segment<D>((i - 1) * D);
      Vec<2 * D> z;
      z.template head<D>() = i == 1 ? x_ : Vec<D>(y.template segment<D>((i - 2) * D));
      z.template tail<D>() = yi;
      if (!grad && !hess) {
        f += single(yi) + pair(z);
        continue;
      }
      auto [fs, gs, hs] = autodiff_hessian<D>(single, yi);
      auto [fp, gp, hp] = autodiff_hessian<2 * D>(pair, z);
      f += fs + fp;
      if (grad) {
        grad->template segment<D>((i - 1) * D) += gs + gp.template tail<D>();
        if (i > 1) grad->template segment<D>((i - 2) * D) += gp.template head<D>();
      }
      if (hess) {
        hess->diagonal[i - 1] += hs + hp.template bottomRightCorner<D, D>();
        if (i > 1) {
          hess->diagonal[i - 2] += hp.template topLeftCorner<D, D>();
          hess->subdiagonal[i - 2] += hp.template bottomLeftCorner<D, D>();
        }
      }
    }
    return std::isnan(f) ? std::numeric_limits<double>::infinity() : f;
  }

  /// F(base + lambda dir) and its derivative d/dlambda = grad F . dir, in one O(n) pass (a
  /// first-order jet in lambda): what the random map needs along its ray.
  double evaluate_along(const Eigen::VectorXd& base, const Eigen::VectorXd& dir, double lambda,
                        double* slope) const {
    const int n = num_blocks();
    using J = Jet2<1>;
    const J lam = J::variable(lambda, 0);
    J f(initial_term(), 1);
    Eigen::Matrix<J, D, 1> prev, cur;
    for (int a = 0; a < D; ++a) prev(a) = J(x_(a), 1);
    for (int i = 1; i <= n; ++i) {
      for (int a = 0; a < D; ++a) cur(a) = base((i - 1) * D + a) + dir((i - 1) * D + a) * lam;
      f = f + single_term(i, cur) + pair_term(i, prev, cur);
      prev = cur;
    }
    if (slope) *slope = f.g(0);
    return std::isnan(f.v) ? std::numeric_limits<double>::infinity() : f.v;
  }

 private:
  // V(y_0, tau_0) dt / (2 gamma): constant in y, but it depends on x (and so on u): keep it.
  double initial_term() const {
    return 0.5 * p_->spec_.dt / p_->gamma_ * p_->model_.running_cost(x_, p_->time(k_));
  }
  // Trapezoid share of V(y_i) (and Phi(y_n) / gamma for the last point).
  template <typename T>
  T single_term(int i, const Eigen::Matrix<T, D, 1>& yi) const {
    const int n = num_blocks();
    const double wv = (i == n ? 0.5 : 1.0) * p_->spec_.dt / p_->gamma_;
    T s = wv * p_->model_.running_cost(yi, p_->time(k_ + i));
    if (i == n) s = s + p_->model_.final_cost(yi) / p_->gamma_;
    return s;
  }
  // |y_i - y_{i-1} - f(y_{i-1}) dt|^2_{Sigma^-1} / (2 dt).
  template <typename T>
  T pair_term(int i, const Eigen::Matrix<T, D, 1>& prev, const Eigen::Matrix<T, D, 1>& cur) const {
    const double dt = p_->spec_.dt;
    const Eigen::Matrix<T, D, 1> r = cur - prev - p_->model_.drift(prev, p_->time(k_ + i - 1)) * dt;
    T q = T(0.0);
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) q = q + r(a) * p_->sigma_inv_(a, b) * r(b);
    return q * (0.5 / dt);
  }

  const Problem* p_;
  Vec<D> x_;
  int k_;
};

}  // namespace implicit::control
