#pragma once
// The double slit problem of path integral control (paper §3.1, Table 1; spec §2.4).
//
// A walker dx = u dt + sqrt(sigma) dW starts at x(0) = 1 and must pass a wall at t1 = 1 through
// one of two slits [-6, -4] or [6, 8]; the cost is E[x(tf)^2 / 2 + integral of r u^2 / 2] with
// tf = 2, and a crash (missing both slits) costs +infinity. With gamma = r sigma the problem is
// solved exactly by log psi (spec §2.4.1); this class gives that exact solution (stably, in log
// space), the discretised path function F of implicit sampling with its closed-form constrained
// minima (one per slit), the estimators of psi, the finite-difference control, and plain Monte
// Carlo for comparison.
//
//   implicit::control::DoubleSlit slit;                         // Table 1 parameters
//   double u = slit.exact_control(1.0, 0.0);                    // -5.109548
//   auto est = slit.estimate_control(1.0, 0, 50, SlitEstimator::kFrozenWall, {.seed = 7});
//   est.u;  est.ess;  est.passed;                               // estimate and diagnostics
//
// Common mistakes (all in the paper, spec E12-E16): the increment variance of the path is
// sigma dt (not gamma dt), Gaussian factors 1/2 are easy to drop, and dropping the weights
// exp(F_hat - F) at a constrained minimum (estimator P) biases u by about 2 %.

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/banded.hpp"
#include "implicit/core/rng.hpp"

namespace implicit::control {

/// An opening [lower, upper] in the wall.
struct Slit {
  double lower = 0.0;
  double upper = 0.0;
  bool contains(double x) const { return x >= lower && x <= upper; }
};

/// Table 1 of the paper. gamma = r sigma (spec E10).
struct DoubleSlitParameters {
  double final_time = 2.0;  ///< tf
  double wall_time = 1.0;   ///< t1, a multiple of dt
  std::array<Slit, 2> slits{{{-6.0, -4.0}, {6.0, 8.0}}};
  double initial_state = 1.0;  ///< x(0)
  double sigma = 1.0;          ///< noise intensity: dx = u dt + sqrt(sigma) dW
  double control_cost = 0.1;   ///< r in the cost r u^2 / 2
  double dt = 0.02;            ///< time step

  double gamma() const { return control_cost * sigma; }
};

/// Throws InvalidArgument naming the first bad parameter: dt, sigma or r not positive, not
/// 0 < t1 < tf, tf or t1 not a multiple of dt, a slit with lower >= upper, slits overlapping or
/// out of order, a non-finite x(0). DoubleSlit and double_slit_problem check with it.
void check_double_slit_parameters(const DoubleSlitParameters& p);

/// The double slit's dynamics and costs in the form the generic estimator of path_integral.hpp
/// takes (dx = u dt + dW, no running cost, final cost x^2 / 2); the wall is not part of the model
/// but a `HardWall` passed beside it (double_slit_problem.hpp builds both from the parameters).
/// Also the simplest nonzero test problem after the wall.
struct FreeWalkerModel {
  /// Zero drift, no running cost, a quadratic end cost: F is quadratic, and with walls the
  /// estimators may sample only the wall values (wall_values.hpp).
  static constexpr bool kLinearQuadratic = true;
  template <typename T>
  Eigen::Matrix<T, 1, 1> drift(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return x * 0.0;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return x(0) * 0.0;
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 1, 1>& x) const {
    return 0.5 * x(0) * x(0);
  }
};

/// How psi is estimated for t < t1 (spec §2.4.4-2.4.5).
enum class SlitEstimator {
  kPaper,       ///< P: dominant slit only, no weights, plain FD-CRN (the paper's; biased)
  kFrozenWall,  ///< W2: both slits, exact weights, FD-CRN with the wall coordinate frozen
  kPlainFd,     ///< W2 with plain FD-CRN (constrained minimiser recomputed at x +- h)
};
std::string_view to_string(SlitEstimator e);

/// Where the reference variables live. Both are exact importance samplers with the same law:
/// the path space draws xi in R^n and maps y = mu + L^{-T} xi (O(n) per sample); the wall space
/// draws only the wall offset delta = (L^{-T} xi)_w ~ N(0, tau^2), which is all the estimator
/// depends on because F(y) = phi_s + nu_s delta + |xi|^2 / 2 at a constrained minimum.
enum class SlitSampling { kPath, kWall };

/// The constrained minimum of F for one slit at state x and grid step k (spec §2.4.3).
struct SlitMinimum {
  double edge = 0.0;  ///< e_s = clamp(m, lower, upper): the path's value at the wall
  double phi = 0.0;   ///< F at the constrained minimiser
  double nu = 0.0;    ///< grad F = nu e_w there (0 when the constraint is inactive)
  bool active = false;
};

/// One estimate of psi and of the control at (x, t_k), with diagnostics.
struct SlitControlEstimate {
  double u = 0.0;         ///< the control estimate
  double log_psi = 0.0;   ///< log psi_hat at x (-inf if no sample passed)
  double ess = 0.0;       ///< effective sample size of the weights at x
  int samples = 0;        ///< samples drawn (over both slits for W2)
  int passed = 0;         ///< samples that passed through their slit
  bool fallback = false;  ///< no sample passed: u is the Laplace control sigma (e - x) / v
};

/// Result of plain Monte Carlo over forward-Euler paths from (x, t).
struct PlainMonteCarloResult {
  int paths = 0;
  int passed = 0;        ///< paths inside a slit at t1
  double log_psi = 0.0;  ///< log of the mean of exp(-cost / gamma); -inf if none passed
};

class DoubleSlit {
 public:
  explicit DoubleSlit(const DoubleSlitParameters& p = {});

  const DoubleSlitParameters& parameters() const { return p_; }
  double gamma() const { return gamma_; }
  int num_steps() const { return num_steps_; }  ///< K = tf / dt
  int wall_step() const { return wall_step_; }  ///< K1 = t1 / dt
  double time(int k) const { return k * p_.dt; }
  bool in_slits(double x) const;

  // ---- Exact solution (spec §2.4.1) ----------------------------------------------------------
  /// log psi(x, t); -inf at t = t1 outside the slits. Throws for t outside [0, tf].
  double exact_log_psi(double x, double t) const;
  /// u(x, t) = sigma d/dx log psi. For t >= t1 the wall is behind: u = -sigma x/(gamma +
  /// sigma(tf-t)).
  double exact_control(double x, double t) const;

  // ---- Discretised path problem at grid step k < K (spec §2.4.3) -------------------------------
  /// Constrained minimum for slit s (0 or 1) at (x, t_k), k < K1.
  SlitMinimum constrained_minimum(double x, int k, int s) const;
  /// As above with the wall value frozen at `edge` (the frozen-wall variant, spec §2.4.5).
  SlitMinimum frozen_minimum(double x, int k, double edge) const;
  /// The minimiser path mu_1..mu_n for a wall value `edge` (i <= w: straight line to the edge;
  /// i > w: the unconstrained optimum after the wall). For k >= K1 `edge` is ignored and the
  /// unconstrained minimiser is returned.
  Eigen::VectorXd minimizer_path(double x, int k, double edge) const;
  /// F(y) = sum (y_i - y_{i-1})^2 / (2 sigma dt) + y_n^2 / (2 gamma), y_0 = x, without the wall.
  double path_function(double x, const Eigen::VectorXd& y) const;
  /// Its constant tridiagonal Hessian H = T / (sigma dt) + e_n e_n^T / gamma for n = K - k.
  BlockTridiagonal<1> path_hessian(int k) const;
  /// log((sigma dt)^{n/2} det L): the normaliser of the path integral, n = K - k.
  double log_normalizer(int k) const;
  /// Index w (1-based) of the wall coordinate y_w = y(t1) in the path at step k < K1.
  int wall_index(int k) const { return wall_step_ - k; }

  // ---- Estimators (spec §2.4.4-2.4.5) --------------------------------------------------------
  /// The control estimate at (x, t_k) from M samples (per slit for W2). Reference variables come
  /// from the stream `key` (its purpose is overridden by purpose::kReference). For k >= K1, F is
  /// quadratic, every weight is 1 and u is the t >= t1 formula (with the path sampler, computed
  /// from samples by FD-CRN). Throws InvalidArgument for M < 1 or k outside [0, K).
  SlitControlEstimate estimate_control(double x, int k, int M, SlitEstimator estimator,
                                       const StreamKey& key,
                                       SlitSampling sampling = SlitSampling::kWall) const;

  /// Closed form of the frozen-wall FD limit: (sum_j w_j Y_{j,w} - x) / (t1 - t) over the
  /// samples of both slits (spec §2.4.5), with the same reference variables as estimate_control.
  double frozen_wall_limit(double x, int k, int M, const StreamKey& key,
                           SlitSampling sampling = SlitSampling::kWall) const;

  /// log psi_hat at (x, t_k) from given wall offsets delta (one array per slit, each ~ N(0,
  /// tau^2)): the 1-D form of estimator W (or P). Exposed for tests of the path code.
  double log_psi_from_offsets(double x, int k, std::span<const double> delta0,
                              std::span<const double> delta1, SlitEstimator estimator) const;

  /// Per-sample log weights log(exp(-F(Y) + |xi|^2/2)) - log normaliser of the path sampler for
  /// slit s (Y = mu_s + L^{-T} xi_j, xi_j the columns of `xi`), -inf when Y_w misses the slit.
  /// Also returns each sample's wall offset delta_j = (L^{-T} xi_j)_w. For tests and Figure 1.
  std::vector<double> path_log_weights(double x, int k, int s, const Eigen::MatrixXd& xi,
                                       std::vector<double>* delta = nullptr,
                                       Eigen::MatrixXd* paths = nullptr) const;

  // ---- Plain Monte Carlo (paper Figure 1, left) ---------------------------------------------
  /// Forward-Euler paths from (x, t_k) with path j drawing from stream (seed, step, j,
  /// kProposal). If `paths` is given, the first `keep` paths are stored (one per column, y_0..y_n).
  PlainMonteCarloResult plain_monte_carlo(double x, int k, int paths, std::uint64_t seed,
                                          std::uint64_t step = 0, Eigen::MatrixXd* kept = nullptr,
                                          int keep = 0) const;

 private:
  void require_step(int k, const char* what) const;
  double tau2(int k) const;  // variance of the wall offset
  double mean_at_wall(double x, int k) const;
  // Path-sampler log weights for wall value `edge` (slit s decides which samples pass).
  void path_weights(double x, int k, int s, double edge, const Eigen::MatrixXd& xi,
                    std::vector<double>& log_w, std::vector<double>* delta,
                    Eigen::MatrixXd* paths) const;
  // log psi_hat from per-slit log weights (W2: both slits; P: slit `dominant` only).
  double combine(const std::vector<double>& lw0, const std::vector<double>& lw1, int M,
                 SlitEstimator estimator, int dominant, double phi_dominant, int k) const;

  DoubleSlitParameters p_;
  double gamma_ = 0.0;
  int num_steps_ = 0;
  int wall_step_ = 0;
  std::vector<BlockTridiagonalCholesky<1>> factors_;  // Cholesky of the path Hessian per step k
};

/// One closed-loop run of spec §2.4.6: exact and estimated controllers driven by the SAME noise.
struct SlitRun {
  Eigen::VectorXd x_exact, x_estimate;  ///< K + 1 states
  Eigen::VectorXd u_exact, u_estimate;  ///< K controls
  double error_x = 0.0;                 ///< |X_IS - X_ex| / |X_ex|
  double error_u = 0.0;                 ///< |U_IS - U_ex| / |U_ex|
  bool crashed_exact = false;           ///< exact trajectory missed the slits at t1
  bool crashed_estimate = false;        ///< estimated trajectory missed the slits at t1
  int fallbacks = 0;                    ///< steps where no sample passed
  double ess_mean = 0.0;                ///< mean ESS over the steps k < K1
};

/// Fills a run's crash flags (x(t1) outside the slits) and its relative errors e_x, e_u from its
/// trajectories (spec §2.4.6); simulate_slit_run ends with it, and so can any other controller's
/// run.
void score_slit_run(const DoubleSlit& slit, SlitRun& run);

/// Runs the closed loop for run number `run`: noise W_k from stream (seed, run, 0,
/// kProcessNoise) (if `noise` is empty) and reference variables from (seed, run, k, kReference).
/// The paper's Table 2 is statistics over many such runs: that aggregation is the experiment's,
/// not the library's (experiments/slit_table.hpp).
SlitRun simulate_slit_run(const DoubleSlit& slit, int samples, SlitEstimator estimator,
                          std::uint64_t seed, std::uint64_t run,
                          SlitSampling sampling = SlitSampling::kWall,
                          const Eigen::VectorXd& noise = {});

}  // namespace implicit::control
