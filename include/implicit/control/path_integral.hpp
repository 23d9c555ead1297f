#pragma once
// Path integral control of your own problem: the generic problem type and estimators.
//
// A stochastic optimal control problem
//
//   dx = f(x, t) dt + G (u dt + Q dW),   cost E[ Phi(x(tf)) + integral (u^T R u / 2 + V(x, t)) dt ]
//
// is linearised by the log transform J = -gamma log psi when condition (8) holds:
// gamma G R^-1 G^T = G Q Q^T G^T =: Sigma. Then psi(x, t) = E[exp(-(Phi + integral V)/gamma)]
// over uncontrolled paths, and the optimal control is u = gamma R^-1 G^T grad_x log psi. This
// header discretises the path (forward Euler, spec §2.2), writes F(y_1..y_n) whose integral
// gives psi, and estimates log psi by plain Monte Carlo or by implicit sampling (banded Newton,
// linear or random map, O(n) per sample); the control comes from central differences with
// common random numbers. Hard walls (the path must cross a^T x(t_w) through one of several
// openings) are handled by one constrained minimum per combination of openings and a Gaussian
// mixture over them.
//
// The model is one type with three members templated on the scalar (for automatic derivatives):
//
// clang-format off
//   struct Model {
//     template <typename T> Eigen::Matrix<T, D, 1> drift(const Eigen::Matrix<T, D, 1>& x, double t) const;
//     template <typename T> T running_cost(const Eigen::Matrix<T, D, 1>& x, double t) const;  // V
//     template <typename T> T final_cost(const Eigen::Matrix<T, D, 1>& x) const;              // Phi
//   };
//   ControlSpec<1, 1> spec;  spec.G << 1;  spec.noise_covariance << 1;  spec.control_cost << 0.1;
//   ControlProblem problem(Model{}, spec);          // checks condition (8), finds gamma = 0.1
//   auto c = estimate_control(problem, x, 0, {.samples = 50}, {.seed = 1});   // c.u, c.psi.ess
//   // A wall at t = 1 with openings (-6, -4) and (6, 8) (the double slit):
//   HardWall<1> wall{.time = 1.0, .openings = {{-6, -4}, {6, 8}}};
//   ControlProblem walled(Model{}, spec, {wall});   // c.psi.modes: one per opening
// clang-format on
//
// Common mistakes: R and Q Q^T that violate condition (8) (the constructor names the entry that
// does not match); noise acting on a subspace only (Sigma singular: integrate over the noisy
// coordinates, see robot_arm.hpp); writing a hard wall as V = +inf in running_cost: that only
// zeroes weights, and with several openings the samples of one Laplace approximation rarely
// reach the other openings. Describe it as a HardWall instead: the estimator then finds one
// constrained minimum per opening and samples a mixture (spec §2.4.3). The random map needs F to
// increase along every ray from its minimiser ("star-shaped", e.g. convex F); with walls it runs
// inside each mode's openings, which is exact for a convex F.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "implicit/core/banded.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::control {

/// The linear parts of a control problem: D states, P controls.
template <int D, int P>
struct ControlSpec {
  Eigen::Matrix<double, D, P> G = Eigen::Matrix<double, D, P>::Zero();  ///< input matrix
  Mat<P> noise_covariance = Mat<P>::Identity();  ///< Q Q^T (the noise enters as G Q dW)
  Mat<P> control_cost = Mat<P>::Identity();      ///< R (symmetric positive definite)
  double horizon = 1.0;                          ///< tf - t0
  double dt = 0.01;                              ///< time step; horizon must be a multiple
};

/// Checks the spec and condition (8); returns gamma and writes Sigma = G Q Q^T G^T. Throws
/// InvalidArgument naming the problem (dt, horizon, R, Q Q^T, the mismatching entry of (8), or a
/// singular Sigma).
template <int D, int P>
double check_control_spec(const ControlSpec<D, P>& s, Mat<D>* sigma_out = nullptr) {
  require(std::isfinite(s.dt) && s.dt > 0.0, "control problem: expected dt > 0, got {}", s.dt);
  const double steps = s.horizon / s.dt;
  require(
      std::isfinite(steps) && steps >= 1.0 && std::abs(steps - std::round(steps)) <= 1e-9 * steps,
      "control problem: expected the horizon to be a positive multiple of dt, got {} / {} = {}",
      s.horizon, s.dt, steps);
  require(s.G.allFinite() && s.noise_covariance.allFinite() && s.control_cost.allFinite(),
          "control problem: expected finite G, Q Q^T and R");
  const Mat<P>& R = s.control_cost;
  require((R - R.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + R.cwiseAbs().maxCoeff()),
          "control problem: expected a symmetric control cost R");
  const Eigen::LLT<Mat<P>> r_llt(R);
  require(r_llt.info() == Eigen::Success,
          "control problem: expected a positive definite control cost R, but its Cholesky "
          "factorisation failed");
  const Mat<P>& N = s.noise_covariance;
  require((N - N.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + N.cwiseAbs().maxCoeff()),
          "control problem: expected a symmetric noise covariance Q Q^T");
  const Eigen::SelfAdjointEigenSolver<Mat<P>> eig(N);
  const double min_eig = eig.eigenvalues().minCoeff();
  require(min_eig >= -1e-12 * (1.0 + eig.eigenvalues().cwiseAbs().maxCoeff()),
          "control problem: expected a positive semi-definite noise covariance Q Q^T, got the "
          "eigenvalue {}",
          min_eig);
  const Mat<D> A = s.G * r_llt.solve(s.G.transpose());  // G R^-1 G^T
  const Mat<D> B = s.G * N * s.G.transpose();           // G Q Q^T G^T
  require(A.trace() > 0.0, "control problem: expected a non-zero input matrix G");
  const double gamma = B.trace() / A.trace();
  require(gamma > 0.0, "control problem: expected noise acting through G, got G Q Q^T G^T = 0");
  const Mat<D> mismatch = gamma * A - B;
  Eigen::Index i = 0, j = 0;
  const double worst = mismatch.cwiseAbs().maxCoeff(&i, &j);
  require(worst <= 1e-9 * (1.0 + B.cwiseAbs().maxCoeff()),
          "control problem: condition (8) gamma G R^-1 G^T = G Q Q^T G^T has no solution: with the "
          "best gamma = {}, entry ({}, {}) is {} on the left and {} on the right (choose R "
          "proportional to (Q Q^T)^-1 on the controlled subspace)",
          gamma, i, j, gamma * A(i, j), B(i, j));
  const Eigen::LLT<Mat<D>> s_llt(B);
  require(s_llt.info() == Eigen::Success,
          "control problem: the noise covariance Sigma = G Q Q^T G^T is singular (noise acts on a "
          "subspace only); integrate over the noisy coordinates as in robot_arm.hpp");
  if (sigma_out) *sigma_out = B;
  return gamma;
}

/// An opening (lower, upper) of a hard wall; either end may be infinite.
struct WallOpening {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool contains(double v) const { return v > lower && v < upper; }
};

/// A hard wall: at the grid time `time` the path must have direction^T x(time) inside one of the
/// `openings` (sorted, disjoint); elsewhere V = +inf. Several walls may be given.
template <int D>
struct HardWall {
  double time = 0.0;                   ///< a grid time in (0, horizon]
  Vec<D> direction = Vec<D>::Unit(0);  ///< a: the wall tests a^T x (default: coordinate 0)
  std::vector<WallOpening> openings;   ///< where a^T x may pass
  bool passes(const Vec<D>& x) const {
    const double v = direction.dot(x);
    for (const auto& o : openings)
      if (o.contains(v)) return true;
    return false;
  }
};

template <int D, int P, typename Model>
class ControlProblem {
 public:
  static constexpr int kStateDim = D;
  static constexpr int kControlDim = P;

  /// Throws InvalidArgument for a bad spec (see check_control_spec) or a bad wall (time not a
  /// grid time in (0, horizon], zero or non-finite direction, no openings, openings empty,
  /// unsorted or overlapping).
  ControlProblem(Model model, const ControlSpec<D, P>& spec, std::vector<HardWall<D>> walls = {})
      : model_(std::move(model)), spec_(spec), walls_(std::move(walls)) {
    gamma_ = check_control_spec(spec_, &sigma_);
    sigma_llt_.compute(sigma_);
    sigma_inv_ = sigma_llt_.solve(Mat<D>::Identity());
    sigma_sqrt_ = sigma_llt_.matrixL();
    log_det_sigma_ = 2.0 * sigma_sqrt_.diagonal().array().log().sum();
    num_steps_ = static_cast<int>(std::round(spec_.horizon / spec_.dt));
    for (std::size_t j = 0; j < walls_.size(); ++j) {
      const auto& w = walls_[j];
      const double r = w.time / spec_.dt, step = std::round(r);
      require(std::isfinite(r) && std::abs(r - step) <= 1e-9 * std::max(1.0, r) && step >= 1.0 &&
                  step <= num_steps_,
              "hard wall {}: expected a time that is a multiple of dt = {} in (0, {}], got {}", j,
              spec_.dt, spec_.horizon, w.time);
      require(w.direction.allFinite() && w.direction.norm() > 0.0,
              "hard wall {}: expected a finite non-zero direction", j);
      require(!w.openings.empty(), "hard wall {}: expected at least one opening, got none", j);
      for (std::size_t o = 0; o < w.openings.size(); ++o) {
        const auto& op = w.openings[o];
        require(!std::isnan(op.lower) && !std::isnan(op.upper) && op.lower < op.upper,
                "hard wall {}, opening {}: expected lower < upper, got ({}, {})", j, o, op.lower,
                op.upper);
        require(o == 0 || w.openings[o - 1].upper <= op.lower,
                "hard wall {}, opening {}: expected sorted disjoint openings, got ({}, {}) after "
                "({}, {})",
                j, o, op.lower, op.upper, w.openings[o - 1].lower, w.openings[o - 1].upper);
      }
      wall_steps_.push_back(static_cast<int>(step));
    }
  }

  const Model& model() const { return model_; }
  const ControlSpec<D, P>& spec() const { return spec_; }
  double gamma() const { return gamma_; }
  const Mat<D>& sigma() const { return sigma_; }
  double dt() const { return spec_.dt; }
  int num_steps() const { return num_steps_; }
  double time(int k) const { return k * spec_.dt; }
  const std::vector<HardWall<D>>& walls() const { return walls_; }
  /// The grid step of wall j.
  int wall_step(std::size_t j) const { return wall_steps_[j]; }

  /// True if the path y_1..y_n from (x, t_k) passes every wall at or after t_k (walls at t_k test
  /// x itself; earlier walls are behind and ignored).
  bool passes_walls(const Vec<D>& x, int k, const Eigen::VectorXd& y) const {
    for (std::size_t j = 0; j < walls_.size(); ++j) {
      const int w = wall_steps_[j] - k;
      if (w < 0) continue;
      const Vec<D> at = w == 0 ? x : Vec<D>(y.template segment<D>((w - 1) * D));
      if (!walls_[j].passes(at)) return false;
    }
    return true;
  }

  /// u = gamma R^-1 G^T grad log psi.
  Vec<P> control_from_gradient(const Vec<D>& grad_log_psi) const {
    const Eigen::LLT<Mat<P>> llt(spec_.control_cost);
    return gamma_ * llt.solve(spec_.G.transpose() * grad_log_psi);
  }

  /// F over y_1..y_n (n = K - k) from y_0 = x at t_k: a banded target with D x D blocks.
  class PathFunction {
   public:
    static constexpr int Block = D;
    PathFunction(const ControlProblem* p, const Vec<D>& x, int k) : p_(p), x_(x), k_(k) {}
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
          return pair_term(i,
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
    T pair_term(int i, const Eigen::Matrix<T, D, 1>& prev,
                const Eigen::Matrix<T, D, 1>& cur) const {
      const double dt = p_->spec_.dt;
      const Eigen::Matrix<T, D, 1> r =
          cur - prev - p_->model_.drift(prev, p_->time(k_ + i - 1)) * dt;
      T q = T(0.0);
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) q = q + r(a) * p_->sigma_inv_(a, b) * r(b);
      return q * (0.5 / dt);
    }

    const ControlProblem* p_;
    Vec<D> x_;
    int k_;
  };

  PathFunction path_function(const Vec<D>& x, int k) const {
    require(k >= 0 && k < num_steps_, "control problem: expected a step in [0, {}), got {}",
            num_steps_, k);
    require(x.allFinite(), "control problem: expected a finite state");
    return PathFunction(this, x, k);
  }

  /// The noise-free forward-Euler path from (x, t_k): a start point for the minimiser.
  Eigen::VectorXd drift_path(const Vec<D>& x, int k) const {
    const int n = num_steps_ - k;
    Eigen::VectorXd y(n * D);
    Vec<D> cur = x;
    for (int i = 1; i <= n; ++i) {
      cur = cur + model_.drift(cur, time(k + i - 1)) * spec_.dt;
      y.template segment<D>((i - 1) * D) = cur;
    }
    return y;
  }

  /// -log of the path-integral normaliser (2 pi dt)^{N/2} (det Sigma)^{n/2}, N = n D.
  double log_normalizer(int n) const {
    return 0.5 * n * D * (kLog2Pi + std::log(spec_.dt)) + 0.5 * n * log_det_sigma_;
  }

  /// Lower Cholesky factor of Sigma (forward-Euler increments are sqrt(dt) Sigma^{1/2} w).
  const Mat<D>& sigma_sqrt() const { return sigma_sqrt_; }

 private:
  Model model_;
  ControlSpec<D, P> spec_;
  std::vector<HardWall<D>> walls_;
  std::vector<int> wall_steps_;
  double gamma_ = 0.0;
  Mat<D> sigma_, sigma_inv_, sigma_sqrt_;
  Eigen::LLT<Mat<D>> sigma_llt_;
  double log_det_sigma_ = 0.0;
  int num_steps_ = 0;
};

enum class PsiMethod {
  kImplicit,    ///< implicit sampling over the path: banded Newton + linear or random map
  kMonteCarlo,  ///< plain Monte Carlo over forward-Euler paths
};

/// How implicit sampling maps a reference sample xi to a path (spec §1.2, §1.3).
enum class SamplingMap {
  kLinear,  ///< y = mu + L^{-T} xi, weight exp(F_hat - F)
  kRandom,  ///< y = mu + lambda L^{-T} xi / |xi| with F(y) - phi = |xi|^2 / 2 (corrected Jacobian)
};

inline std::string_view to_string(SamplingMap m) {
  return m == SamplingMap::kLinear ? "linear" : "random";
}

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

/// One estimate of log psi with diagnostics.
struct PsiEstimate {
  double log_psi = -std::numeric_limits<double>::infinity();
  double ess = 0.0;
  int samples = 0;
  int wall_hits = 0;     ///< samples with F = +inf or outside a wall opening (zero weight)
  int map_failures = 0;  ///< random map: samples whose scalar equation had no root (zero weight)
  double relative_se = 0.0;  ///< sd(w) / (sqrt(M) mean w): the SE of log psi_hat, to first order
  MinimizeStatus status = MinimizeStatus::kConverged;  ///< of the minimiser (worst mode with walls)
  Eigen::VectorXd minimizer;    ///< mu (implicit only): warm start for nearby states
  std::vector<WallMode> modes;  ///< with hard walls ahead: the mixture components
};

struct EstimatorOptions {
  int samples = 50;
  PsiMethod method = PsiMethod::kImplicit;
  SamplingMap map = SamplingMap::kLinear;
  /// With hard walls: at x +- h keep each mode's wall values a^T y_w and mixture weights from x
  /// (spec §2.4.5, "frozen wall"). Still an exact importance sampler, and a sample cannot switch
  /// between passing and hitting the wall between x + h and x - h (that switch makes the finite
  /// difference spike).
  bool freeze_walls = true;
  double fd_step = 1e-4;  ///< h = fd_step max(1, |x|_inf) for the central differences
  MinimizeOptions minimize{};
};

namespace detail {
inline PsiEstimate summarize(std::vector<double>& lw) {
  PsiEstimate e;
  e.samples = static_cast<int>(lw.size());
  for (double l : lw) e.wall_hits += std::isfinite(l) ? 0 : 1;
  e.log_psi = log_mean_exp(lw);
  if (e.wall_hits < e.samples) {
    std::vector<double> w(lw.size());
    e.ess = normalize_log_weights(lw, w).ess;
    e.relative_se = relative_standard_error(lw);
  }
  return e;
}

/// Cholesky of h, adding Levenberg damping until it is positive definite. The factor then
/// defines a Gaussian proposal that is not the Laplace approximation, but the weights stay exact.
template <int B>
bool factor_damped(const BlockTridiagonal<B>& h, BlockTridiagonalCholesky<B>& factor) {
  if (factor.compute(h)) return true;
  double lambda = 1e-8;
  for (const auto& d : h.diagonal) lambda = std::max(lambda, 1e-8 * d.cwiseAbs().maxCoeff());
  BlockTridiagonal<B> damped;
  for (int i = 0; i < 60; ++i, lambda *= 10.0) {
    damped = h;
    damped.add_to_diagonal(lambda);
    if (factor.compute(damped)) return true;
  }
  return false;
}

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

/// A linear equality a^T y_block = value (block is 0-based).
template <int D>
struct WallConstraint {
  int block = 0;
  Vec<D> a = Vec<D>::Zero();
  double value = 0.0;
};

/// Damped Newton for min F(y) subject to the equalities C^T y = e (C sparse, one column per
/// constraint), by the range-space method: Z = H^{-1} C and the small Schur complement
/// S = C^T Z, so each step stays O(n) with the banded factor. The start is first moved onto the
/// constraints by the smallest H-norm correction; every later step has C^T step = 0, so the line
/// search on F itself is valid. `nu` returns the multipliers (grad F + C nu = 0 at the solution).
template <typename PathF>
BandedMinimizeResult<PathF::Block> minimize_with_equalities(
    const PathF& f, const Eigen::VectorXd& x0,
    const std::vector<WallConstraint<PathF::Block>>& cons, const MinimizeOptions& options,
    Eigen::VectorXd& nu) {
  constexpr int D = PathF::Block;
  const int m = static_cast<int>(cons.size());
  nu.setZero(m);
  if (m == 0) return minimize_banded(f, x0, options);
  const int nb = f.num_blocks(), N = nb * D;
  BandedMinimizeResult<D> r;
  r.x = x0;
  r.gradient.resize(N);
  r.hessian.resize(nb);
  Eigen::MatrixXd Z(N, m), S(m, m);
  Eigen::LLT<Eigen::MatrixXd> s_llt;
  Eigen::VectorXd p(N), step(N), trial(N), ctp(m);
  auto c_dot = [&](int j, const auto& v) {
    return cons[j].a.dot(v.template segment<D>(cons[j].block * D));
  };
  auto factor_and_project = [&]() {
    if (!factor_damped(r.hessian, r.factor)) return false;
    for (int j = 0; j < m; ++j) {
      auto col = Z.col(j);
      col.setZero();
      col.template segment<D>(cons[j].block * D) = cons[j].a;
      r.factor.solve_in_place(col);
    }
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) S(i, j) = c_dot(i, Z.col(j));
    s_llt.compute(S);
    return s_llt.info() == Eigen::Success;
  };
  auto evaluate = [&]() {
    r.value = f.evaluate(r.x, &r.gradient, &r.hessian);
    ++r.evaluations;
    return std::isfinite(r.value) && r.gradient.allFinite() && r.hessian.all_finite();
  };
  if (!evaluate()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  if (!factor_and_project()) {
    r.status = MinimizeStatus::kNotPositiveDefinite;
    return r;
  }
  for (int j = 0; j < m; ++j) ctp(j) = cons[j].value - c_dot(j, r.x);
  r.x += Z * s_llt.solve(ctp);
  if (!evaluate()) {
    r.status = MinimizeStatus::kNonFinite;
    return r;
  }
  r.status = MinimizeStatus::kMaxIterations;
  for (r.iterations = 0; r.iterations < options.max_iterations; ++r.iterations) {
    if (!factor_and_project()) {
      r.status = MinimizeStatus::kNotPositiveDefinite;
      break;
    }
    p = r.gradient;
    r.factor.solve_in_place(p);
    for (int j = 0; j < m; ++j) ctp(j) = c_dot(j, p);
    nu = -s_llt.solve(ctp);
    step = -p - Z * nu;
    trial = r.gradient;  // the reduced gradient grad F + C nu
    for (int j = 0; j < m; ++j) trial.template segment<D>(cons[j].block * D) += nu(j) * cons[j].a;
    if (trial.cwiseAbs().maxCoeff() <= options.gradient_tolerance) {
      r.status = MinimizeStatus::kConverged;
      break;
    }
    if (!(r.gradient.dot(step) < 0.0)) {  // no feasible descent left at machine precision
      r.status = step.cwiseAbs().maxCoeff() <=
                         1e3 * options.step_tolerance * (1.0 + r.x.cwiseAbs().maxCoeff())
                     ? MinimizeStatus::kConverged
                     : MinimizeStatus::kLineSearchFailed;
      break;
    }
    if (implicit::detail::newton_line_step(f, r, step, trial, options) !=
        implicit::detail::StepOutcome::kContinue)
      break;
  }
  if (r.status != MinimizeStatus::kNonFinite && !factor_damped(r.hessian, r.factor))
    r.status = MinimizeStatus::kNotPositiveDefinite;
  return r;
}

enum class RayOutcome { kOk, kWall, kFailed };

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

/// The random map's scalar equation F(mu + lambda d) = target along one ray (spec §1.3): bracket
/// [0, hi] with hi doubled from sqrt(rho), then Newton safeguarded by bisection, to 1e-12
/// relative. kWall: F jumps to +inf before reaching the level (no root: the sample has zero
/// weight, which is exact, since no point of the ray beyond the jump has mass).
template <typename PathF>
RayOutcome solve_ray(const PathF& f, const Eigen::VectorXd& mu, const Eigen::VectorXd& d,
                     double target, double rho, double& lambda, double& slope) {
  auto g_of = [&](double l, double* s) { return f.evaluate_along(mu, d, l, s) - target; };
  double lo = 0.0, hi = std::sqrt(rho);
  double ghi = g_of(hi, nullptr);
  for (int doublings = 0; !(ghi > 0.0); ++doublings) {
    if (doublings > 200) return RayOutcome::kFailed;
    lo = hi;
    hi *= 2.0;
    ghi = g_of(hi, nullptr);
  }
  lambda = std::min(std::sqrt(rho), 0.5 * (lo + hi));
  if (lambda <= lo) lambda = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double g = g_of(lambda, &slope);
    if (g > 0.0)
      hi = lambda;
    else
      lo = lambda;
    double next = std::isfinite(g) && slope > 0.0 ? lambda - g / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double change = std::abs(next - lambda);
    lambda = next;
    if (change <= 1e-12 * lambda || hi - lo <= 1e-12 * hi) break;
  }
  const double g = g_of(lambda, &slope);
  // A root has |g| at rounding level; a finite g far from 0 with an infinite F just above means
  // the level lies beyond a jump to +inf (a wall along the ray).
  if (!std::isfinite(g) || std::abs(g) > 1e-6 * (1.0 + target))
    return std::isfinite(g_of(hi, nullptr)) ? RayOutcome::kFailed : RayOutcome::kWall;
  if (!(std::abs(slope) > 0.0) || !std::isfinite(slope)) return RayOutcome::kFailed;
  return RayOutcome::kOk;
}
}  // namespace detail

/// log psi_hat(x, t_k) by implicit sampling: minimise F (warm start `warm` if non-empty, else the
/// drift path), factor its banded Hessian (damped until SPD if needed: the weights stay exact),
/// then M samples with xi from stream (key.seed, key.step, key.index, kReference): the linear
/// map y = mu + L^{-T} xi, or the random map (spec §1.3, corrected Jacobian) along the ray
/// L^{-T} xi. Reusing the same key at a nearby x gives common random numbers.
///
/// With hard walls ahead (problem.walls() after t_k): one mode per combination of openings, each
/// with its constrained minimum (see constrained_modes), a Gaussian mixture over them weighted
/// by their Laplace masses, component choice from stream (..., kMixture), weights
/// exp(-F) / q with the true F (0 at a wall). `frozen` (from an estimate at a nearby x) keeps
/// that estimate's modes: their wall values a^T y_w and mixture weights. With the random map
/// and walls, a sample chooses mode c with probability pi_c and runs the random map of F
/// restricted to c's openings; its weight is divided by pi_c (the random map has no proposal
/// density in closed form, so the modes cannot share samples as the linear mixture does).
template <typename Problem>
PsiEstimate estimate_log_psi_implicit(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                      int k, int M, const StreamKey& key,
                                      const Eigen::VectorXd& warm = {},
                                      const MinimizeOptions& options = {},
                                      SamplingMap map = SamplingMap::kLinear,
                                      const std::vector<WallMode>* frozen = nullptr) {
  constexpr int D = Problem::kStateDim;
  constexpr double kNegInf = -std::numeric_limits<double>::infinity();
  require(M >= 1, "path integral estimator: expected at least 1 sample, got {}", M);
  const auto F = problem.path_function(x, k);
  const int n = F.num_blocks(), N = n * D;
  PsiEstimate dead;  // psi = 0: every sample has zero weight
  dead.samples = M;
  dead.wall_hits = M;
  std::vector<int> ahead;
  for (std::size_t j = 0; j < problem.walls().size(); ++j) {
    const int w = problem.wall_step(j);
    if (w == k && !problem.walls()[j].passes(x)) return dead;  // at the wall, outside an opening
    if (w > k) ahead.push_back(static_cast<int>(j));
  }
  const Eigen::VectorXd start = warm.size() == N ? warm : problem.drift_path(x, k);
  Rng rng({key.seed, key.step, key.index, purpose::kReference});
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd xi(N), y(N);

  if (ahead.empty()) {
    auto r = minimize_banded(F, start, options);
    if (r.status == MinimizeStatus::kNonFinite) {
      dead.status = r.status;
      dead.minimizer = r.x;
      return dead;
    }
    if (!r.factor.ok()) detail::factor_damped(r.hessian, r.factor);
    const double log_det_L = r.factor.log_det_L();
    int failures = 0;
    if (map == SamplingMap::kLinear) {
      const double log_norm = problem.log_normalizer(n) - 0.5 * N * kLog2Pi + log_det_L;
      for (int j = 0; j < M; ++j) {
        rng.fill_normal(xi);
        y = xi;
        r.factor.upper_solve_in_place(y);
        y += r.x;
        const double fy = F.evaluate(y, nullptr, nullptr);
        lw[static_cast<std::size_t>(j)] =
            std::isfinite(fy) ? -fy + 0.5 * xi.squaredNorm() - log_norm : kNegInf;
      }
    } else {
      // log w = (N/2) log 2pi - phi - log det L + (1 - N/2) log rho + (N - 1) log lambda
      //         - log |grad F . d|, minus the path normaliser (spec §1.3, §2.2).
      const double log_const = 0.5 * N * kLog2Pi - r.value - log_det_L - problem.log_normalizer(n);
      Eigen::VectorXd d(N);
      for (int j = 0; j < M; ++j) {
        rng.fill_normal(xi);
        const double rho = xi.squaredNorm();
        d = xi / std::sqrt(rho);
        r.factor.upper_solve_in_place(d);
        double lambda = 0.0, slope = 0.0;
        const auto out = detail::solve_ray(F, r.x, d, r.value + 0.5 * rho, rho, lambda, slope);
        failures += out == detail::RayOutcome::kFailed ? 1 : 0;
        lw[static_cast<std::size_t>(j)] = out == detail::RayOutcome::kOk
                                              ? log_const + (1.0 - 0.5 * N) * std::log(rho) +
                                                    (N - 1.0) * std::log(lambda) -
                                                    std::log(std::abs(slope))
                                              : kNegInf;
      }
    }
    PsiEstimate out = detail::summarize(lw);
    out.map_failures = failures;
    out.wall_hits -= failures;
    out.status = r.status;
    out.minimizer = std::move(r.x);
    return out;
  }

  const auto& walls = problem.walls();
  const int A = static_cast<int>(ahead.size());
  std::vector<WallMode> modes;
  if (frozen) {
    modes = *frozen;
    for (const auto& md : modes)
      require(md.walls == ahead && md.minimizer.size() == N,
              "path integral estimator: the frozen modes belong to another step or problem");
  } else {
    std::size_t count = 1;
    for (int a : ahead) {
      count *= walls[static_cast<std::size_t>(a)].openings.size();
      require(count <= 256,
              "path integral estimator: expected at most 256 combinations of wall openings, got "
              "more than {}",
              count / walls[static_cast<std::size_t>(a)].openings.size());
    }
    modes.resize(count);
    for (std::size_t c = 0; c < count; ++c) {
      modes[c].walls = ahead;
      modes[c].openings.resize(static_cast<std::size_t>(A));
      std::size_t rest = c;
      for (int i = A - 1; i >= 0; --i) {
        const std::size_t no = walls[static_cast<std::size_t>(ahead[i])].openings.size();
        modes[c].openings[static_cast<std::size_t>(i)] = static_cast<int>(rest % no);
        rest /= no;
      }
      modes[c].clamped.assign(static_cast<std::size_t>(A), 0);
    }
  }
  auto block_of = [&](int i) {
    return problem.wall_step(static_cast<std::size_t>(ahead[i])) - k - 1;
  };
  auto wall_value = [&](int i, const Eigen::VectorXd& v) {
    return walls[static_cast<std::size_t>(ahead[i])].direction.dot(
        v.template segment<D>(block_of(i) * D));
  };
  // The unconstrained minimiser: the start of every mode's constrained search.
  Eigen::VectorXd free_min = start;
  if (!frozen) {
    const auto r = minimize_banded(F, start, options);
    if (r.status != MinimizeStatus::kNonFinite) free_min = r.x;
  }
  std::vector<BlockTridiagonalCholesky<D>> factors(modes.size());
  std::vector<double> log_det(modes.size(), 0.0);
  Eigen::VectorXd nu;
  std::vector<detail::WallConstraint<D>> cons;
  PsiEstimate out;
  for (std::size_t c = 0; c < modes.size(); ++c) {
    WallMode& md = modes[c];
    BandedMinimizeResult<D> r;
    if (frozen) {
      cons.clear();
      for (int i = 0; i < A; ++i)
        cons.push_back({block_of(i), walls[static_cast<std::size_t>(ahead[i])].direction,
                        md.wall_values[static_cast<std::size_t>(i)]});
      r = detail::minimize_with_equalities(F, md.minimizer, cons, options, nu);
    } else {
      // Active set: minimise with the clamped walls held at their edges; clamp every wall whose
      // value leaves its opening (to the nearest edge), release clamped walls whose multiplier
      // pulls back into the opening, repeat. For a convex F and one wall the first clamp is
      // already exact (the minimum over a convex set lies on the boundary when the free
      // minimiser is outside it); with several walls or a non-convex F this is a safeguarded
      // heuristic, capped at 2 A + 2 rounds. An inexact centre costs efficiency only: the
      // weights use the true F, so the estimator stays unbiased for any centre.
      // Two starts: the free minimiser, and the free minimiser translated along each wall's
      // direction so that it passes through the mode's openings (the shift ramps up linearly
      // from the previous wall and is kept after the wall). For a non-convex F (an obstacle to
      // pass on either side) clamping only the wall point can leave the rest of the path on the
      // wrong side, a poor local minimum; the lower constrained F wins.
      auto search = [&](const Eigen::VectorXd& from, std::vector<int>& clamped) {
        BandedMinimizeResult<D> r;
        Eigen::VectorXd at = from;
        for (int round = 0; round < 2 * A + 2; ++round) {
          cons.clear();
          for (int i = 0; i < A; ++i) {
            if (clamped[static_cast<std::size_t>(i)] == 0) continue;
            const auto& op =
                walls[static_cast<std::size_t>(ahead[i])]
                    .openings[static_cast<std::size_t>(md.openings[static_cast<std::size_t>(i)])];
            cons.push_back({block_of(i), walls[static_cast<std::size_t>(ahead[i])].direction,
                            clamped[static_cast<std::size_t>(i)] < 0 ? op.lower : op.upper});
          }
          r = detail::minimize_with_equalities(F, at, cons, options, nu);
          if (r.status == MinimizeStatus::kNonFinite) break;
          at = r.x;
          bool changed = false;
          for (int i = 0; i < A; ++i) {
            if (clamped[static_cast<std::size_t>(i)] != 0) continue;
            const auto& op =
                walls[static_cast<std::size_t>(ahead[i])]
                    .openings[static_cast<std::size_t>(md.openings[static_cast<std::size_t>(i)])];
            const double v = wall_value(i, at);
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
              if (side * nu(j) < 0.0) {
                side = 0;
                changed = true;
              }
              ++j;
            }
          }
          if (!changed) break;
        }
        return r;
      };
      std::vector<int> clamped_free = md.clamped, clamped_start = md.clamped;
      r = search(free_min, clamped_free);
      md.clamped = clamped_free;
      Eigen::VectorXd shifted = free_min;
      std::vector<int> order(static_cast<std::size_t>(A));
      for (int i = 0; i < A; ++i) order[static_cast<std::size_t>(i)] = i;
      std::sort(order.begin(), order.end(),
                [&](int p, int q) { return block_of(p) < block_of(q); });
      int previous = -1;
      for (int i : order) {
        const auto& wall = walls[static_cast<std::size_t>(ahead[i])];
        const auto& op =
            wall.openings[static_cast<std::size_t>(md.openings[static_cast<std::size_t>(i)])];
        const double v = wall_value(i, shifted);
        const double target = std::clamp(v, op.lower, op.upper);
        const int w = block_of(i);
        if (target != v && w > previous) {
          const Vec<D> delta = (target - v) / wall.direction.squaredNorm() * wall.direction;
          for (int b = previous + 1; b < n; ++b)
            shifted.template segment<D>(b * D) +=
                std::min(1.0, static_cast<double>(b - previous) / (w - previous)) * delta;
        }
        previous = std::max(previous, w);
      }
      if ((shifted - free_min).cwiseAbs().maxCoeff() > 0.0) {
        auto other = search(shifted, clamped_start);
        const bool other_ok = other.status != MinimizeStatus::kNonFinite && other.factor.ok();
        const bool r_ok = r.status != MinimizeStatus::kNonFinite && r.factor.ok();
        if (other_ok && (!r_ok || other.value < r.value)) {
          r = std::move(other);
          md.clamped = clamped_start;
        }
      }
    }
    md.status = r.status;
    md.minimizer = r.x;
    md.samples = 0;
    md.wall_hits = 0;
    md.wall_values.resize(static_cast<std::size_t>(A));
    for (int i = 0; i < A; ++i) md.wall_values[static_cast<std::size_t>(i)] = wall_value(i, r.x);
    const bool usable = r.status != MinimizeStatus::kNonFinite && r.factor.ok();
    md.phi = usable ? r.value : std::numeric_limits<double>::infinity();
    if (usable) {
      factors[c] = std::move(r.factor);
      log_det[c] = factors[c].log_det_L();
    }
    if (!frozen) md.log_weight = usable ? -md.phi - log_det[c] : kNegInf;
    if (!usable) md.log_weight = kNegInf;
    if (md.status != MinimizeStatus::kConverged) out.status = md.status;
  }
  // Normalise the mixture weights and build the cumulative table for the component choice.
  std::vector<double> log_pi(modes.size());
  for (std::size_t c = 0; c < modes.size(); ++c) log_pi[c] = modes[c].log_weight;
  const double lse = log_sum_exp(log_pi);
  if (!std::isfinite(lse)) {
    dead.status = out.status;
    dead.modes = std::move(modes);
    return dead;
  }
  std::vector<double> cumulative(modes.size());
  double acc = 0.0;
  for (std::size_t c = 0; c < modes.size(); ++c) {
    log_pi[c] -= lse;
    modes[c].log_weight = log_pi[c];
    acc += std::exp(log_pi[c]);
    cumulative[c] = acc;
  }
  Rng pick({key.seed, key.step, key.index, purpose::kMixture});
  const double log_norm = problem.log_normalizer(n) - 0.5 * N * kLog2Pi;
  Eigen::VectorXd diff(N), d(N);
  int failures = 0;
  std::vector<double> a_mu(static_cast<std::size_t>(A)), a_d(static_cast<std::size_t>(A));
  for (int j = 0; j < M; ++j) {
    const double u = pick.uniform() * acc;
    std::size_t c = 0;
    while (c + 1 < modes.size() && !(u < cumulative[c])) ++c;
    while (!std::isfinite(log_pi[c]) && c > 0) --c;  // never choose a weight-0 component
    rng.fill_normal(xi);
    ++modes[c].samples;
    double& l = lw[static_cast<std::size_t>(j)];
    if (map == SamplingMap::kRandom) {
      // Random map inside mode c only: F restricted to the paths through c's openings (+inf
      // elsewhere), integrated along rays from mu_c. That region is convex and mu_c is the
      // constrained minimum, so for a convex F every ray sees F - phi_c increase: the map is
      // one-to-one onto the region. psi = sum_c Z_c, and choosing c with probability pi_c
      // makes w / pi_c unbiased for it.
      const double rho = xi.squaredNorm();
      d = xi / std::sqrt(rho);
      factors[c].upper_solve_in_place(d);
      const WallMode& md = modes[c];
      for (int i = 0; i < A; ++i) {
        const auto& a = walls[static_cast<std::size_t>(ahead[i])].direction;
        a_mu[static_cast<std::size_t>(i)] =
            a.dot(md.minimizer.template segment<D>(block_of(i) * D));
        a_d[static_cast<std::size_t>(i)] = a.dot(d.template segment<D>(block_of(i) * D));
      }
      auto inside = [&](double lambda) {
        for (int i = 0; i < A; ++i) {
          const auto& op =
              walls[static_cast<std::size_t>(ahead[i])]
                  .openings[static_cast<std::size_t>(md.openings[static_cast<std::size_t>(i)])];
          if (!op.contains(a_mu[static_cast<std::size_t>(i)] +
                           lambda * a_d[static_cast<std::size_t>(i)]))
            return false;
        }
        return true;
      };
      const detail::RestrictedPath restricted{F, inside};
      double lambda = 0.0, slope = 0.0;
      const auto ray =
          detail::solve_ray(restricted, md.minimizer, d, md.phi + 0.5 * rho, rho, lambda, slope);
      if (ray != detail::RayOutcome::kOk) {
        if (ray == detail::RayOutcome::kWall)
          ++modes[c].wall_hits;
        else
          ++failures;
        l = kNegInf;
        continue;
      }
      l = 0.5 * N * kLog2Pi - md.phi - log_det[c] + (1.0 - 0.5 * N) * std::log(rho) +
          (N - 1.0) * std::log(lambda) - std::log(std::abs(slope)) - log_pi[c] -
          problem.log_normalizer(n);
      continue;
    }
    y = xi;
    factors[c].upper_solve_in_place(y);
    y += modes[c].minimizer;
    const double fy = problem.passes_walls(x, k, y) ? F.evaluate(y, nullptr, nullptr)
                                                    : std::numeric_limits<double>::infinity();
    if (!std::isfinite(fy)) {
      ++modes[c].wall_hits;
      l = kNegInf;
      continue;
    }
    // log q(y) = log sum_c pi_c N(y; mu_c, H_c^{-1}), streamed (no allocation).
    double top = kNegInf, sum = 0.0;
    for (std::size_t i = 0; i < modes.size(); ++i) {
      if (!std::isfinite(log_pi[i])) continue;
      double t;
      if (i == c) {
        t = log_pi[i] + log_det[i] - 0.5 * xi.squaredNorm();
      } else {
        diff = y - modes[i].minimizer;
        t = log_pi[i] + log_det[i] - 0.5 * detail::upper_norm2(factors[i], diff);
      }
      if (t > top) {
        sum = sum * std::exp(top - t) + 1.0;
        top = t;
      } else {
        sum += std::exp(t - top);
      }
    }
    l = -fy - (top + std::log(sum)) - log_norm;
  }
  PsiEstimate result = detail::summarize(lw);
  result.map_failures = failures;
  result.wall_hits -= failures;
  result.status = out.status;
  result.modes = std::move(modes);
  const auto best = std::max_element(
      result.modes.begin(), result.modes.end(),
      [](const WallMode& a, const WallMode& b) { return a.log_weight < b.log_weight; });
  result.minimizer = best->minimizer;
  return result;
}

/// log psi_hat(x, t_k) by plain Monte Carlo: M forward-Euler paths, path j from stream
/// (key.seed, key.step, key.index * M + j, kProposal). Hard walls zero the paths that miss them.
template <typename Problem>
PsiEstimate estimate_log_psi_monte_carlo(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                         int k, int M, const StreamKey& key) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 path, got {}", M);
  const auto F = problem.path_function(x, k);  // validates k and x
  const int n = F.num_blocks();
  const double dt = problem.dt(), g = problem.gamma();
  const Mat<D> scale = problem.sigma_sqrt() * std::sqrt(dt);
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd path(n * D);
  const bool walled = !problem.walls().empty();
  for (int j = 0; j < M; ++j) {
    Rng rng(
        {key.seed, key.step, key.index * static_cast<std::uint64_t>(M) + j, purpose::kProposal});
    Vec<D> y = x;
    double cost = 0.5 * dt * problem.model().running_cost(y, problem.time(k));
    for (int i = 1; i <= n; ++i) {
      y = y + problem.model().drift(y, problem.time(k + i - 1)) * dt +
          scale * rng.normal_vector<D>();
      if (walled) path.template segment<D>((i - 1) * D) = y;
      cost += (i == n ? 0.5 : 1.0) * dt * problem.model().running_cost(y, problem.time(k + i));
    }
    cost += problem.model().final_cost(y);
    if (walled && !problem.passes_walls(x, k, path)) cost = std::numeric_limits<double>::infinity();
    lw[static_cast<std::size_t>(j)] =
        std::isfinite(cost) ? -cost / g : -std::numeric_limits<double>::infinity();
  }
  return detail::summarize(lw);
}

template <int P>
struct ControlEstimate {
  Vec<P> u = Vec<P>::Zero();
  PsiEstimate psi;      ///< at x
  bool defined = true;  ///< false if log psi_hat was -inf at some x +- h e_i
  MinimizeStatus worst_status = MinimizeStatus::kConverged;
};

/// u = gamma R^-1 G^T grad log psi_hat by central differences with common random numbers: the
/// same reference variables at x + h e_i and x - h e_i, minimisers warm-started at mu(x).
template <typename Problem>
ControlEstimate<Problem::kControlDim> estimate_control(const Problem& problem,
                                                       const Vec<Problem::kStateDim>& x, int k,
                                                       const EstimatorOptions& o,
                                                       const StreamKey& key) {
  constexpr int D = Problem::kStateDim;
  const std::vector<WallMode>* frozen = nullptr;
  auto psi = [&](const Vec<D>& xp, const Eigen::VectorXd& warm) {
    return o.method == PsiMethod::kImplicit
               ? estimate_log_psi_implicit(problem, xp, k, o.samples, key, warm, o.minimize, o.map,
                                           frozen)
               : estimate_log_psi_monte_carlo(problem, xp, k, o.samples, key);
  };
  ControlEstimate<Problem::kControlDim> c;
  c.psi = psi(x, Eigen::VectorXd());
  if (o.freeze_walls && !c.psi.modes.empty()) frozen = &c.psi.modes;
  c.worst_status = c.psi.status;
  const double h = o.fd_step * std::max(1.0, x.cwiseAbs().maxCoeff());
  Vec<D> grad = Vec<D>::Zero();
  for (int i = 0; i < D; ++i) {
    Vec<D> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    const auto ep = psi(xp, c.psi.minimizer), em = psi(xm, c.psi.minimizer);
    if (ep.status != MinimizeStatus::kConverged) c.worst_status = ep.status;
    if (em.status != MinimizeStatus::kConverged) c.worst_status = em.status;
    if (!std::isfinite(ep.log_psi) || !std::isfinite(em.log_psi)) {
      c.defined = false;
      continue;
    }
    grad(i) = (ep.log_psi - em.log_psi) / (2.0 * h);
  }
  c.u = problem.control_from_gradient(grad);
  return c;
}

/// Receding-horizon closed loop: x_{k+1} = x_k + (f + G u_k) dt + G Q sqrt(dt) W_k with the
/// noise realisation `noise` (D x K, columns W_k ~ N(0, I) mapped through Sigma^{1/2}).
template <typename Problem>
struct ClosedLoopResult {
  std::vector<Vec<Problem::kStateDim>> x;
  std::vector<Vec<Problem::kControlDim>> u;
  std::vector<PsiEstimate> psi;
};

template <typename Problem>
ClosedLoopResult<Problem> simulate_closed_loop(const Problem& problem,
                                               const Vec<Problem::kStateDim>& x0,
                                               const Eigen::MatrixXd& noise,
                                               const EstimatorOptions& o, std::uint64_t seed,
                                               std::uint64_t run = 0) {
  constexpr int D = Problem::kStateDim;
  const int K = problem.num_steps();
  require(noise.rows() == D && noise.cols() == K,
          "closed loop: expected a {} x {} noise matrix, got {} x {}", D, K, noise.rows(),
          noise.cols());
  ClosedLoopResult<Problem> r;
  r.x.push_back(x0);
  const double sdt = std::sqrt(problem.dt());
  for (int k = 0; k < K; ++k) {
    const auto c =
        estimate_control(problem, r.x.back(), k, o, {seed, run, static_cast<std::uint64_t>(k), 0});
    r.u.push_back(c.u);
    r.psi.push_back(c.psi);
    const Vec<D>& x = r.x.back();
    const Vec<D> w = noise.col(k);
    r.x.push_back(
        x + (problem.model().drift(x, problem.time(k)) + problem.spec().G * c.u) * problem.dt() +
        problem.sigma_sqrt() * w * sdt);
  }
  return r;
}

}  // namespace implicit::control
