#pragma once
// The path function of a control problem with partial noise (spec §2.2, "Partial noise"): the
// state is x = (z, v) with the noise and the control acting on the last Dv coordinates v only
// (velocities driven by forces, say), so Sigma is singular and the path has a density over the
// noisy coordinates alone. The noise-free ones follow them deterministically by forward Euler,
// z_i = z_{i-1} + dt f_z(x_{i-1}), and
//
//   F(v_1..v_n) = sum_i |v_i - v_{i-1} - dt f_v(x_{i-1})|^2_{Sigma_v^-1} / (2 dt)
//                 + trapezoid of V / gamma + Phi(x_n) / gamma.
//
// z_i depends on every earlier v, so the Hessian is dense: the factor is DenseFactor (O(N^3) per
// Newton step, N = n Dv). It is assembled by the chain rule through the Jacobians of the z_i,
// with each term's derivatives by automatic differentiation; blocks that vanish (a term that
// does not depend on z) are skipped, so when z enters only the final cost (a robot arm after
// inverse dynamics) the assembly is O(N^2). The second derivatives of f_z are left out: the
// Hessian is exact when the noise-free drift is affine in x (positions integrating velocities)
// and a Gauss-Newton Hessian otherwise; the implicit sampling weights are exact either way.

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// F over the noisy coordinates v_1..v_n (n = K - k, every step resolved) from x at t_k for the
/// problem `Problem` (a ControlProblem with Dv < D, which grants access to its model and
/// Sigma_v^-1).
template <int D, int Dv, typename Problem>
class PartialNoisePathFunction {
 public:
  static constexpr int Dz = D - Dv;  ///< noise-free coordinates, first in the state
  static constexpr int Block = Dv;   ///< path entries per step
  using Factor = DenseFactor<Eigen::Dynamic>;

  PartialNoisePathFunction(const Problem* p, const Vec<D>& x, int k)
      : p_(p), x_(x), k_(k), n_(p->path_length(k)), dt_(p->spec_.dt) {}
  int num_blocks() const { return n_; }
  int dimension() const { return n_ * Dv; }
  const Vec<D>& start() const { return x_; }
  int start_step() const { return k_; }

  double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* grad, Eigen::MatrixXd* hess) const {
    const int N = dimension();
    if (grad) grad->setZero(N);
    if (hess) hess->setZero(N, N);
    const bool derivatives = grad || hess;
    // Jacobians of z_{i-1} and z_i with respect to y: only the first (i - 1) Dv columns of z_i's
    // are non-zero (z_1 is fixed by x).
    Eigen::MatrixXd jz_prev, jz_cur;
    if (derivatives) {
      jz_prev.setZero(Dz, N);
      jz_cur.setZero(Dz, N);
    }
    double f = 0.5 * dt_ / p_->gamma_ * p_->model_.running_cost(x_, p_->time(k_));
    Vec<D> prev = x_, cur;
    for (int i = 1; i <= n_; ++i) {
      cur.template head<Dz>() = next_noise_free(prev, i);
      cur.template tail<Dv>() = y.template segment<Dv>((i - 1) * Dv);
      if (!derivatives) {
        f += term(i, prev, cur);
        prev = cur;
        continue;
      }
      propagate_jacobian(prev, i, jz_prev, jz_cur);
      Vec<2 * D> w;
      w << prev, cur;
      auto fn = [&](const auto& a) {
        using T = std::decay_t<decltype(a(0))>;
        return term(i, Eigen::Matrix<T, D, 1>(a.template head<D>()),
                    Eigen::Matrix<T, D, 1>(a.template tail<D>()));
      };
      const auto [value, g, h] = autodiff_hessian<2 * D>(fn, w);
      f += value;
      accumulate(i, g, h, jz_prev, jz_cur, grad, hess);
      prev = cur;
      jz_prev.swap(jz_cur);
    }
    return std::isnan(f) ? std::numeric_limits<double>::infinity() : f;
  }

  /// F(base + lambda dir) and d/dlambda in one O(n) pass (a first-order jet in lambda, exact:
  /// the z_i carry the jet through f_z).
  double evaluate_along(const Eigen::VectorXd& base, const Eigen::VectorXd& dir, double lambda,
                        double* slope) const {
    using J = Jet2<1>;
    const J lam = J::variable(lambda, 0);
    J f(0.5 * dt_ / p_->gamma_ * p_->model_.running_cost(x_, p_->time(k_)), 1);
    Eigen::Matrix<J, D, 1> prev, cur;
    for (int a = 0; a < D; ++a) prev(a) = J(x_(a), 1);
    for (int i = 1; i <= n_; ++i) {
      const Eigen::Matrix<J, D, 1> step = p_->model_.drift(prev, p_->time(k_ + i - 1));
      for (int a = 0; a < Dz; ++a) cur(a) = prev(a) + step(a) * dt_;
      for (int a = 0; a < Dv; ++a)
        cur(Dz + a) = base((i - 1) * Dv + a) + dir((i - 1) * Dv + a) * lam;
      f = f + term(i, prev, cur);
      prev = cur;
    }
    if (slope) *slope = f.g(0);
    return std::isnan(f.v) ? std::numeric_limits<double>::infinity() : f.v;
  }

 private:
  // z_i = z_{i-1} + dt f_z(x_{i-1}, t_{i-1}).
  Vec<Dz> next_noise_free(const Vec<D>& prev, int i) const {
    const Vec<D> f = p_->model_.drift(prev, p_->time(k_ + i - 1));
    return prev.template head<Dz>() + dt_ * f.template head<Dz>();
  }

  // jz_cur = jz_prev + dt (A_z jz_prev + A_v S_{i-1}), A = d f_z / dx at x_{i-1} and S_{i-1} the
  // selector of v_{i-1} (none for i = 1: v_0 is x's).
  void propagate_jacobian(const Vec<D>& prev, int i, const Eigen::MatrixXd& jz_prev,
                          Eigen::MatrixXd& jz_cur) const {
    const int cols = (i - 2) * Dv;  // non-zero columns of z_{i-1}'s Jacobian
    Eigen::Matrix<double, Dz, D> a;
    for (int r = 0; r < Dz; ++r) {
      auto fr = [&](const auto& s) { return p_->model_.drift(s, p_->time(k_ + i - 1))(r); };
      a.row(r) = std::get<1>(autodiff_hessian<D>(fr, prev)).transpose();
    }
    if (cols > 0) {
      jz_cur.leftCols(cols) = jz_prev.leftCols(cols);
      jz_cur.leftCols(cols).noalias() += dt_ * a.template leftCols<Dz>() * jz_prev.leftCols(cols);
    }
    if (i >= 2) jz_cur.template middleCols<Dv>(cols) = dt_ * a.template rightCols<Dv>();
  }

  // Adds the term's gradient g and Hessian h over w = (z_{i-1}, v_{i-1}, z_i, v_i) through the
  // chain rule: the z rows are dense Jacobians, the v rows select one block (v_0 none).
  void accumulate(int i, const Vec<2 * D>& g, const Mat<2 * D>& h, const Eigen::MatrixXd& jz_prev,
                  const Eigen::MatrixXd& jz_cur, Eigen::VectorXd* grad,
                  Eigen::MatrixXd* hess) const {
    const int c = (i - 1) * Dv;  // non-zero columns of the z Jacobians
    const int zs[2] = {0, D};    // offsets of z_{i-1}, z_i in w
    const int vs[2] = {Dz, D + Dz};
    const int vcol[2] = {(i - 2) * Dv, (i - 1) * Dv};  // y columns of v_{i-1}, v_i
    const Eigen::MatrixXd* jz[2] = {&jz_prev, &jz_cur};
    for (int s = 0; s < 2; ++s) {
      if (s == 0 && i == 1) continue;  // v_0 is fixed
      if (grad) grad->template segment<Dv>(vcol[s]) += g.template segment<Dv>(vs[s]);
    }
    if (grad && c > 0)
      for (int s = 0; s < 2; ++s)
        grad->head(c).noalias() += jz[s]->leftCols(c).transpose() * g.template segment<Dz>(zs[s]);
    if (!hess) return;
    for (int s = 0; s < 2; ++s) {
      if (s == 0 && i == 1) continue;
      for (int t = 0; t < 2; ++t) {
        if (t == 0 && i == 1) continue;
        hess->template block<Dv, Dv>(vcol[s], vcol[t]) += h.template block<Dv, Dv>(vs[s], vs[t]);
      }
    }
    if (c == 0) return;
    for (int s = 0; s < 2; ++s) {
      for (int t = 0; t < 2; ++t) {
        const Eigen::Matrix<double, Dz, Dz> hzz = h.template block<Dz, Dz>(zs[s], zs[t]);
        if (!hzz.isZero(0.0))  // zero unless the term depends on z: skip the O(c^2) update
          hess->topLeftCorner(c, c).noalias() +=
              jz[s]->leftCols(c).transpose() * hzz * jz[t]->leftCols(c);
        const Eigen::Matrix<double, Dz, Dv> hzv = h.template block<Dz, Dv>(zs[s], vs[t]);
        if (hzv.isZero(0.0)) continue;
        // Both off-diagonal blocks directly: a c x Dv temporary would allocate per term.
        hess->block(0, vcol[t], c, Dv).noalias() += jz[s]->leftCols(c).transpose() * hzv;
        hess->block(vcol[t], 0, Dv, c).noalias() += hzv.transpose() * jz[s]->leftCols(c);
      }
    }
  }

  // The terms of step i: the transition's Gaussian density of v and the trapezoid share of
  // V(x_i) (half at the horizon), plus Phi(x_n) / gamma at the horizon.
  template <typename T>
  T term(int i, const Eigen::Matrix<T, D, 1>& prev, const Eigen::Matrix<T, D, 1>& cur) const {
    const bool last = i == n_;
    const Eigen::Matrix<T, D, 1> f = p_->model_.drift(prev, p_->time(k_ + i - 1));
    Eigen::Matrix<T, Dv, 1> r;
    for (int a = 0; a < Dv; ++a) r(a) = cur(Dz + a) - prev(Dz + a) - f(Dz + a) * dt_;
    T q = T(0.0);
    for (int a = 0; a < Dv; ++a)
      for (int b = 0; b < Dv; ++b) q = q + r(a) * p_->noise_inv_(a, b) * r(b);
    T s = q * (0.5 / dt_) +
          (last ? 0.5 : 1.0) * dt_ / p_->gamma_ * p_->model_.running_cost(cur, p_->time(k_ + i));
    if (last) s = s + p_->model_.final_cost(cur) / p_->gamma_;
    return s;
  }

  const Problem* p_;
  Vec<D> x_;
  int k_;
  int n_;
  double dt_;
};

}  // namespace implicit::control
