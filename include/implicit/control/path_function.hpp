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
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// Where the path of the path integral is resolved (its unknowns y_i).
enum class PathGrid {
  kEveryStep,  ///< at every grid time after the current one (the default)
  /// Only at the walls' times and the horizon. Exact when the drift and the running cost vanish:
  /// the forward-Euler increments between two resolved times are then Gaussian and sum to one
  /// increment of covariance Sigma (t' - t), so psi is unchanged and the sampler works in a few
  /// dimensions instead of K. Otherwise it is a coarser discretisation of the same problem.
  kWallsAndHorizon,
};

/// F over y_1..y_n from y_0 = x at t_k for the problem `Problem` (a ControlProblem, which grants
/// access to its model, Sigma^-1 and time grid): a banded target with D x D blocks. y_i sits at
/// the grid step steps_[i - 1]: k + i on every step, fewer points with PathGrid::kWallsAndHorizon.
template <int D, typename Problem>
class PathFunction {
 public:
  static constexpr int Block = D;
  using Factor = BandedFactor<D>;  ///< the Hessian's factor model (core/gaussian_factor.hpp)
  PathFunction(const Problem* p, const Vec<D>& x, int k)
      : p_(p),
        x_(x),
        k_(k),
        n_(p->path_length(k)),
        steps_(p->path_steps(k)),
        uniform_(p->spec_.path_grid == PathGrid::kEveryStep),
        dt_(p->spec_.dt),
        share_(1.0 * dt_ / p->gamma_),
        share_last_(0.5 * dt_ / p->gamma_) {}
  int num_blocks() const { return n_; }
  int dimension() const { return n_ * D; }
  const Vec<D>& start() const { return x_; }
  int start_step() const { return k_; }  ///< k: y_0 = x at t_k

  double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* grad,
                  BlockTridiagonal<D>* hess) const {
    const int n = n_;
    if (grad) grad->setZero(n * D);
    if (hess) hess->resize(n);
    double f = initial_term();
    for (int i = 1; i <= n; ++i) {
      const Segment seg = segment(i);
      auto single = [&](const auto& yi) { return single_term(seg, yi); };
      auto pair = [&](const auto& z) {
        return pair_term(seg,
                         Eigen::Matrix<std::decay_t<decltype(z(0))>, D, 1>(z.template head<D>()),
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
      const Segment seg = segment(i);
      f = f + single_term(seg, cur) + pair_term(seg, prev, cur);
      prev = cur;
    }
    if (slope) *slope = f.g(0);
    return std::isnan(f.v) ? std::numeric_limits<double>::infinity() : f.v;
  }

 private:
  // The grid step of y_i (y_0 = x at step k) and the interval dt_i before y_i.
  int step(int i) const { return i == 0 ? k_ : steps_[i - 1]; }
  double interval(int i) const { return (step(i) - step(i - 1)) * p_->spec_.dt; }

  // What the terms of y_i need, computed once per block outside the (automatically
  // differentiated) terms, which stay small enough to be inlined.
  struct Segment {
    double dt;      // dt_i, the interval before y_i
    double t_from;  // the time of y_{i-1}
    double t;       // the time of y_i
    double share;   // the trapezoid share (dt_i + dt_{i+1}) / 2 of V(y_i), over gamma
    bool last;      // i = n: Phi(y_n) / gamma too
  };
  Segment segment(int i) const {
    const bool last = i == n_;
    if (uniform_)  // every step resolved: the common case, kept as cheap as a constant dt
      return {dt_, p_->time(k_ + i - 1), p_->time(k_ + i), last ? share_last_ : share_, last};
    const double dt = interval(i);
    return {dt, p_->time(step(i - 1)), p_->time(step(i)),
            0.5 * (dt + (last ? 0.0 : interval(i + 1))) / p_->gamma_, last};
  }

  // V(y_0, tau_0) dt_1 / (2 gamma): constant in y, but it depends on x (and so on u): keep it.
  double initial_term() const {
    return 0.5 * interval(1) / p_->gamma_ * p_->model_.running_cost(x_, p_->time(k_));
  }
  // The trapezoid share of V(y_i) (and Phi(y_n) / gamma for the last point).
  template <typename T>
  T single_term(const Segment& seg, const Eigen::Matrix<T, D, 1>& yi) const {
    T s = seg.share * p_->model_.running_cost(yi, seg.t);
    if (seg.last) s = s + p_->model_.final_cost(yi) / p_->gamma_;
    return s;
  }
  // |y_i - y_{i-1} - f(y_{i-1}) dt_i|^2_{Sigma^-1} / (2 dt_i).
  template <typename T>
  T pair_term(const Segment& seg, const Eigen::Matrix<T, D, 1>& prev,
              const Eigen::Matrix<T, D, 1>& cur) const {
    const double dt = seg.dt;
    const Eigen::Matrix<T, D, 1> r = cur - prev - p_->model_.drift(prev, seg.t_from) * dt;
    T q = T(0.0);
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) q = q + r(a) * p_->sigma_inv_(a, b) * r(b);
    return q * (0.5 / dt);
  }

  const Problem* p_;
  Vec<D> x_;
  int k_;
  int n_;
  const int* steps_;  // grid steps of y_1..y_n (owned by the problem)
  bool uniform_;      // every grid step resolved: steps_[i - 1] = k + i
  double dt_, share_, share_last_;
};

}  // namespace implicit::control
