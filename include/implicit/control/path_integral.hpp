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
// linear map); the control comes from central differences with common random numbers.
//
// The model is one type with three members templated on the scalar (for automatic derivatives):
//
//   struct Model {
//     template <typename T> Eigen::Matrix<T, D, 1> drift(const Eigen::Matrix<T, D, 1>& x, double t)
//     const; template <typename T> T running_cost(const Eigen::Matrix<T, D, 1>& x, double t) const;
//     // V template <typename T> T final_cost(const Eigen::Matrix<T, D, 1>& x) const; // Phi
//   };
//   ControlSpec<1, 1> spec;  spec.G << 1;  spec.noise_covariance << 1;  spec.control_cost << 0.1;
//   ControlProblem problem(Model{}, spec);          // checks condition (8), finds gamma = 0.1
//   auto c = estimate_control(problem, x, 0, {.samples = 50}, {.seed = 1});   // c.u, c.psi.ess
//
// Common mistakes: R and Q Q^T that violate condition (8) (the constructor names the entry that
// does not match); noise acting on a subspace only (Sigma singular: integrate over the noisy
// coordinates, see robot_arm.hpp); hard walls (V = +inf) with several openings need one
// constrained minimum per opening (see double_slit.hpp): here a wall only zeroes weights.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
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

template <int D, int P, typename Model>
class ControlProblem {
 public:
  static constexpr int kStateDim = D;
  static constexpr int kControlDim = P;

  ControlProblem(Model model, const ControlSpec<D, P>& spec)
      : model_(std::move(model)), spec_(spec) {
    gamma_ = check_control_spec(spec_, &sigma_);
    sigma_llt_.compute(sigma_);
    sigma_inv_ = sigma_llt_.solve(Mat<D>::Identity());
    sigma_sqrt_ = sigma_llt_.matrixL();
    log_det_sigma_ = 2.0 * sigma_sqrt_.diagonal().array().log().sum();
    num_steps_ = static_cast<int>(std::round(spec_.horizon / spec_.dt));
  }

  const Model& model() const { return model_; }
  const ControlSpec<D, P>& spec() const { return spec_; }
  double gamma() const { return gamma_; }
  const Mat<D>& sigma() const { return sigma_; }
  double dt() const { return spec_.dt; }
  int num_steps() const { return num_steps_; }
  double time(int k) const { return k * spec_.dt; }

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
      const double dt = p_->spec_.dt, g = p_->gamma_;
      const auto& model = p_->model_;
      if (grad) grad->setZero(n * D);
      if (hess) hess->resize(n);
      // V(y_0, tau_0): constant in y, but it depends on x (and so on u): keep it.
      double f = 0.5 * dt / g * model.running_cost(x_, p_->time(k_));
      for (int i = 1; i <= n; ++i) {
        const double t_prev = p_->time(k_ + i - 1), t_i = p_->time(k_ + i);
        const double wv = (i == n ? 0.5 : 1.0) * dt / g;  // trapezoid weights of V(y_i)
        const bool last = i == n;
        auto single = [&](const auto& yi) {
          using T = std::decay_t<decltype(yi(0))>;
          T s = wv * model.running_cost(yi, t_i);
          if (last) s = s + model.final_cost(yi) / g;
          return s;
        };
        auto pair = [&](const auto& z) {
          using T = std::decay_t<decltype(z(0))>;
          const Eigen::Matrix<T, D, 1> prev = z.template head<D>();
          const Eigen::Matrix<T, D, 1> cur = z.template tail<D>();
          const Eigen::Matrix<T, D, 1> r = cur - prev - model.drift(prev, t_prev) * dt;
          T q = T(0.0);
          for (int a = 0; a < D; ++a)
            for (int b = 0; b < D; ++b) q = q + r(a) * p_->sigma_inv_(a, b) * r(b);
          return q * (0.5 / dt);
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

   private:
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
  double gamma_ = 0.0;
  Mat<D> sigma_, sigma_inv_, sigma_sqrt_;
  Eigen::LLT<Mat<D>> sigma_llt_;
  double log_det_sigma_ = 0.0;
  int num_steps_ = 0;
};

enum class PsiMethod {
  kImplicit,    ///< implicit sampling over the path: banded Newton + linear map
  kMonteCarlo,  ///< plain Monte Carlo over forward-Euler paths
};

/// One estimate of log psi with diagnostics.
struct PsiEstimate {
  double log_psi = -std::numeric_limits<double>::infinity();
  double ess = 0.0;
  int samples = 0;
  int wall_hits = 0;         ///< samples with F = +inf (zero weight)
  double relative_se = 0.0;  ///< sd(w) / (sqrt(M) mean w): the SE of log psi_hat, to first order
  MinimizeStatus status = MinimizeStatus::kConverged;  ///< of the minimiser (implicit only)
  Eigen::VectorXd minimizer;  ///< mu (implicit only): warm start for nearby states
};

struct EstimatorOptions {
  int samples = 50;
  PsiMethod method = PsiMethod::kImplicit;
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
}  // namespace detail

/// log psi_hat(x, t_k) by implicit sampling: minimise F (warm start `warm` if non-empty, else the
/// drift path), factor its banded Hessian (damped until SPD if needed: the weights stay exact),
/// then M samples y = mu + L^{-T} xi with xi from stream (key.seed, key.step, key.index,
/// kReference). Reusing the same key at a nearby x gives common random numbers.
template <typename Problem>
PsiEstimate estimate_log_psi_implicit(const Problem& problem, const Vec<Problem::kStateDim>& x,
                                      int k, int M, const StreamKey& key,
                                      const Eigen::VectorXd& warm = {},
                                      const MinimizeOptions& options = {}) {
  constexpr int D = Problem::kStateDim;
  require(M >= 1, "path integral estimator: expected at least 1 sample, got {}", M);
  const auto F = problem.path_function(x, k);
  const int n = F.num_blocks();
  const Eigen::VectorXd start = warm.size() == n * D ? warm : problem.drift_path(x, k);
  auto r = minimize_banded(F, start, options);
  PsiEstimate e;
  e.status = r.status;
  e.minimizer = r.x;
  if (r.status == MinimizeStatus::kNonFinite) {
    e.samples = M;
    e.wall_hits = M;
    return e;
  }
  if (!r.factor.ok()) {
    double lambda = 1e-8;
    for (const auto& d : r.hessian.diagonal)
      lambda = std::max(lambda, 1e-8 * d.cwiseAbs().maxCoeff());
    for (int i = 0; i < 60 && !r.factor.ok(); ++i, lambda *= 10.0) {
      auto h = r.hessian;
      h.add_to_diagonal(lambda);
      r.factor.compute(h);
    }
  }
  const double log_norm = problem.log_normalizer(n) - 0.5 * n * D * kLog2Pi + r.factor.log_det_L();
  Rng rng({key.seed, key.step, key.index, purpose::kReference});
  std::vector<double> lw(static_cast<std::size_t>(M));
  Eigen::VectorXd xi(n * D), y(n * D);
  for (int j = 0; j < M; ++j) {
    rng.fill_normal(xi);
    y = xi;
    r.factor.upper_solve_in_place(y);
    y += r.x;
    const double fy = F.evaluate(y, nullptr, nullptr);
    lw[static_cast<std::size_t>(j)] = std::isfinite(fy) ? -fy + 0.5 * xi.squaredNorm() - log_norm
                                                        : -std::numeric_limits<double>::infinity();
  }
  PsiEstimate out = detail::summarize(lw);
  out.status = e.status;
  out.minimizer = std::move(e.minimizer);
  return out;
}

/// log psi_hat(x, t_k) by plain Monte Carlo: M forward-Euler paths, path j from stream
/// (key.seed, key.step, key.index * M + j, kProposal).
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
  for (int j = 0; j < M; ++j) {
    Rng rng(
        {key.seed, key.step, key.index * static_cast<std::uint64_t>(M) + j, purpose::kProposal});
    Vec<D> y = x;
    double cost = 0.5 * dt * problem.model().running_cost(y, problem.time(k));
    for (int i = 1; i <= n; ++i) {
      y = y + problem.model().drift(y, problem.time(k + i - 1)) * dt +
          scale * rng.normal_vector<D>();
      cost += (i == n ? 0.5 : 1.0) * dt * problem.model().running_cost(y, problem.time(k + i));
    }
    cost += problem.model().final_cost(y);
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
  auto psi = [&](const Vec<D>& xp, const Eigen::VectorXd& warm) {
    return o.method == PsiMethod::kImplicit
               ? estimate_log_psi_implicit(problem, xp, k, o.samples, key, warm, o.minimize)
               : estimate_log_psi_monte_carlo(problem, xp, k, o.samples, key);
  };
  ControlEstimate<Problem::kControlDim> c;
  c.psi = psi(x, Eigen::VectorXd());
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
