#pragma once
// The implicit smoother of data assimilation (docs/specification.md §3.14, "Implicit smoother"):
// implicit sampling of a window's initial state for a perfect (deterministic) model, cycled
// through the data one observation at a time.
//
//   implicit::da::SmootherOptions o{.members = 30, .lag = 4, .inflation = 1.05};
//   implicit::da::ImplicitSmoother s(problem, o);   // problem.Q empty: a perfect model
//   s.initialize(x0, 2.0 * Eigen::MatrixXd::Identity(3, 3));
//   for (const auto& y : observations) {
//     const auto& a = s.assimilate(y);   // a.mean: the filtering analysis at y's time
//   }
//
// Cycle k keeps members x0_j with weights w_j at the window start t_s, s = max(0, k - L), that
// represent p(x_s | y_1..y_{k-1}). It fits the background N(b, B) (weighted mean and
// inflation^2 times the weighted covariance), minimises
//   F(x0) = 1/2 |x0 - b|^2_{B^-1} + 1/2 |y_k - H M^l(x0)|^2_{R^-1}
//           + 1/2 log det 2 pi B + 1/2 log det 2 pi R,      l = k - s = min(k, L),
// by Gauss-Newton (core's newton_minimize with the Hessian B^-1 + G^T R^-1 G, G = H dM^l/dx0)
// from b and from the heaviest members, samples x0_j = mu + L^-T xi_j (the linear map) with
// core's exact implicit weight, and reports the weighted mean of M^l(x0_j). Every observation
// enters exactly one F: older ones act through the background, which is fitted at the window
// start where the smoothed distribution is narrow (nearly Gaussian). When k > L the members first
// move one interval forward (the window shifts by one cycle).
//
// With a bandwidth h < 1 the background is a kernel mixture instead: the members are resampled
// (systematic, uniforms (seed, k, 0, kResampling)) and member j is redrawn from its own
// kernel's F, the background term 1/2 |x0 - c_j|^2_{(h^2 B)^-1}, c_j = a x0_j + (1 - a) b,
// a = sqrt(1 - h^2) (the mixture keeps the members' mean and covariance), by its own Newton run
// and the linear map with its exact weight. Each kernel is narrower than B, so its F is nearer
// to quadratic and the samples keep the non-Gaussian shape the members carry; the cost is one
// Newton run per member.
//
// Draws: initial members (seed, 0, j, kInitial), reference variables (seed, k, j, kReference).
// Members are sampled in parallel with per-member scratch; every reduction is serial in member
// order, so results are bit-identical for any number of threads.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/da/filters.hpp"
#include "implicit/da/model.hpp"

namespace implicit::da {

struct SmootherOptions {
  int members = 10;        ///< N, at least 2
  int lag = 3;             ///< L, window length in observation cycles, at least 1
  double inflation = 1.0;  ///< multiplies the background's anomalies (B by its square), >= 1
  int starts = 3;          ///< Newton starts: b and the starts - 1 heaviest members, >= 1
  /// h in (0, 1]. 1: one Gaussian background N(b, B) for every member. Below 1: a kernel
  /// mixture, one kernel N(a x0_j + (1 - a) b, h^2 B) per member (a = sqrt(1 - h^2), so the
  /// mixture keeps the members' mean and covariance), each with its own F and Newton.
  double bandwidth = 1.0;
  std::uint64_t seed = 1;

  /// Throws InvalidArgument naming the option (N < 2, lag < 1, inflation < 1 or NaN, starts < 1
  /// or > N + 1, bandwidth outside (0, 1], a stochastic model: the smoother assumes a perfect
  /// model).
  void validate(const Problem& p) const;
};

/// What F of one window needs: the background N(b, B) (B by its lower Cholesky factor and its
/// inverse), the lower Cholesky factor of R, the observation y at lag l >= 1 and the constant
/// log_norm = 1/2 log det 2 pi B + 1/2 log det 2 pi R.
struct WindowTerms {
  Eigen::VectorXd b, y;
  Eigen::MatrixXd b_lower, b_inv, r_lower;
  int lag = 1;
  double log_norm = 0.0;
  /// Sets log_norm from b_lower and r_lower.
  void set_log_norm();
};

/// F of one window and its Gauss-Newton derivatives. `evaluate` moves a copy of x0 through l
/// intervals of the model in the caller's scratch, so one objective per thread. The Hessian
/// returned is B^-1 + G^T R^-1 G, G = H dM^l/dx0 (Gauss-Newton: the model's second derivative
/// is left out; the implicit weights stay exact for any SPD factor).
class WindowObjective {
 public:
  using Vector = Eigen::VectorXd;
  using Hessian = Eigen::MatrixXd;

  struct Scratch {
    ForecastWorkspace forecast;
    Eigen::VectorXd state, residual, dx, xi;
    Eigen::MatrixXd step_jacobian, jacobian, product, hr;
  };

  /// p and t must outlive the objective.
  WindowObjective(const Problem& p, const WindowTerms& t, Scratch& scratch)
      : p_(&p), t_(&t), b_(&t.b), s_(&scratch) {}
  /// The same F with the background centred at `centre` instead of t.b (a kernel of the
  /// mixture: the members' kernels share t's covariance, observation and lag). centre must
  /// outlive the objective.
  WindowObjective(const Problem& p, const WindowTerms& t, const Vector& centre, Scratch& scratch)
      : p_(&p), t_(&t), b_(&centre), s_(&scratch) {}

  /// F(x0); with grad / hess also its gradient and the Gauss-Newton Hessian. After the call
  /// scratch.state holds M^l(x0). +inf when the forecast leaves the finite numbers.
  double evaluate(const Vector& x0, Vector* grad, Hessian* hess) const;

 private:
  const Problem* p_;
  const WindowTerms* t_;
  const Vector* b_;  ///< the background's centre
  Scratch* s_;
};

/// Sizes a scratch for problem p.
void prepare_scratch(const Problem& p, WindowObjective::Scratch& s);

class ImplicitSmoother {
 public:
  /// Validates the problem and the options (throws InvalidArgument).
  ImplicitSmoother(Problem problem, SmootherOptions options);

  /// Members drawn from N(mean, cov), equal weights (streams (seed, 0, j, kInitial)).
  void initialize(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov);
  /// The given members (one per column) at time 0, equal weights.
  void initialize(const Eigen::MatrixXd& members);

  /// Shifts the window if it is full, then assimilates y (throws InvalidArgument for a wrong
  /// size or a NaN, or a background covariance that is not finite). Cycles count from 1.
  const Analysis& assimilate(const Eigen::VectorXd& y);

  long cycle() const { return cycle_; }
  /// The window-start time's cycle index s (0 before the window is full).
  long window_start() const { return cycle_ > options_.lag ? cycle_ - options_.lag : 0; }
  /// The members at the window start (columns) and their normalised weights.
  Eigen::MatrixXd members() const;
  std::span<const double> weights() const { return weights_; }
  /// The members moved to the last observation's time (M^l(x0_j)), same weights.
  Eigen::MatrixXd window_end_members() const;
  /// The background of the last cycle: b and B (inflated).
  const Eigen::VectorXd& background_mean() const { return terms_.b; }
  const Eigen::MatrixXd& background_cov() const { return cov_; }
  /// The minimiser mu of the last cycle's F (bandwidth 1 only: the kernels' minima are not
  /// kept, and this stays empty).
  const Eigen::VectorXd& mode() const { return mu_; }
  const SmootherOptions& options() const { return options_; }

 private:
  void fit_background();
  void minimise();
  void sample();
  void sample_kernels();
  void read_off();

  Problem problem_;
  SmootherOptions options_;
  std::vector<Eigen::VectorXd> x0_, end_;  ///< members at the window start and at y's time
  std::vector<double> weights_, log_w_;
  std::vector<WindowObjective::Scratch> scratch_;
  std::vector<std::size_t> order_, ancestors_;
  WindowTerms kernel_terms_;              ///< the kernels' shared terms (bandwidth < 1) ...
  std::vector<Eigen::VectorXd> centres_;  ///< ... and each member's kernel centre
  std::vector<double> uniforms_;
  WindowTerms terms_;
  Eigen::MatrixXd cov_, h_lower_;
  Eigen::VectorXd mu_;
  double log_det_l_ = 0.0;  ///< log det of h_lower_ (1/2 log det of the Hessian at mu)
  Analysis analysis_;
  long cycle_ = 0;
  bool initialized_ = false;
};

}  // namespace implicit::da
