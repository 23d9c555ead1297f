#pragma once
// Minimising a function by stochastic optimal control (paper §3.3, Table 4, Figure 5; spec §2.6).
//
// To minimise f, steer dx = u dt + sqrt(sigma) dW so as to minimise E[f(x(tf)) + integral of
// R|u|^2/2]: the noise explores valleys that a local optimiser (Newton) cannot leave. Each time
// step is one receding-horizon path integral control evaluation with implicit sampling over the
// remaining path y_1..y_n in R^2:
//
//   F(y) = sum |y_i - y_{i-1}|^2 / (2 sigma dt) + f(y_n) / gamma,   gamma = sigma R (spec E20).
//
// The estimator is the generic one (estimators.hpp, controller.hpp) on HimmelblauModel. For a
// fixed end point z = y_n the optimal path is a straight line, so the minimiser also comes from
// the 2-D function G(z) = |z - x|^2/(2 sigma n dt) + f(z)/gamma: himmelblau_laplace computes it
// that way, an independent check of the generic path minimum and the start of its search.
//
//   implicit::control::HimmelblauProblem pb;                          // R = sigma = 0.01, dt = 1
//   auto est = implicit::control::himmelblau_control(pb, pb.x0, 0, 50, pb.x0, {.seed = 3});
//   est.u;   // about (-0.1389649, 0.0358407)
//
// Common mistake: forgetting log det L(x) in the finite difference of log psi_hat; unlike the
// double slit, the Hessian of F depends on x here (through grad^2 f at the end point).

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "implicit/control/problem.hpp"
#include "implicit/core/banded.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// Himmelblau's function f(x) = (x1^2 + x2 - 11)^2 + (x1 + x2^2 - 7)^2 with analytic gradient
/// and Hessian (either pointer may be null).
double himmelblau(const Vec<2>& x, Vec<2>* grad = nullptr, Mat<2>* hess = nullptr);

/// Newton's method on f with full steps (no line search), as in Table 4: x_0..x_iterations.
std::vector<Vec<2>> himmelblau_newton(const Vec<2>& x0, int iterations);

struct HimmelblauProblem {
  double control_cost = 0.01;  ///< R (times the identity)
  double sigma = 0.01;         ///< noise intensity
  double dt = 1.0;
  double final_time = 20.0;
  Vec<2> x0{-1.0, -4.0};

  double gamma() const { return sigma * control_cost; }
  int num_steps() const;  ///< tf / dt; throws unless a positive integer
  void validate() const;
};

/// The Laplace approximation of F at state x with n = K - k steps to go.
struct HimmelblauLaplace {
  Vec<2> x = Vec<2>::Zero();    ///< y_0
  Vec<2> end = Vec<2>::Zero();  ///< z* = mu_n, the minimiser of G
  double phi = 0.0;             ///< min F = G(z*)
  int n = 0;
  BlockTridiagonalCholesky<2> factor;  ///< Cholesky of the Hessian of F at mu
  double log_det_L = 0.0;
  MinimizeStatus status = MinimizeStatus::kConverged;
  /// mu_i = x + (z* - x) i / n, stacked (2n entries).
  Eigen::VectorXd path() const;
};

/// Minimises G from `warm` (damped Newton) and factorises the Hessian of F at the minimiser.
/// If the Hessian is not positive definite the minimiser status says so and a damped Hessian
/// is factorised instead (the weights stay exact for any SPD H).
HimmelblauLaplace himmelblau_laplace(const HimmelblauProblem& pb, const Vec<2>& x, int k,
                                     const Vec<2>& warm);

/// F(y) for the path y (2n entries) from x.
double himmelblau_path_function(const HimmelblauProblem& pb, const Vec<2>& x,
                                const Eigen::VectorXd& y);

/// Himmelblau's problem as a generic control problem (problem.hpp): no drift, no running cost,
/// final cost f, G = I, Q Q^T = sigma I, R = R I (so gamma = sigma R by condition (8)). The
/// estimator and the closed loop below run on it, through the same estimate_control a user's
/// problem goes through.
struct HimmelblauModel {
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return x * 0.0;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return x(0) * 0.0;
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    const T a = x(0) * x(0) + x(1) - 11.0;
    const T b = x(0) + x(1) * x(1) - 7.0;
    return a * a + b * b;
  }
};
using HimmelblauControlProblem = ControlProblem<2, 2, HimmelblauModel>;

/// Throws InvalidArgument for a bad problem (HimmelblauProblem::validate).
HimmelblauControlProblem himmelblau_control_problem(const HimmelblauProblem& pb);

struct HimmelblauEstimate {
  Vec<2> u = Vec<2>::Zero();          ///< sigma grad_x log psi_hat (FD-CRN)
  Vec<2> laplace_u = Vec<2>::Zero();  ///< (z* - x) / (n dt), the Laplace control
  double log_psi = 0.0;               ///< log psi_hat at x
  double ess = 0.0;
  Vec<2> end = Vec<2>::Zero();                         ///< z*(x), warm start for the next step
  MinimizeStatus status = MinimizeStatus::kConverged;  ///< worst over the 5 minimisations
};

/// One control evaluation at (x, t_k) with M samples (linear map) and FD-CRN in both
/// coordinates: estimate_control on himmelblau_control_problem(pb), with the path minimisation
/// started on the straight line from x to `warm` (the minimiser over paths with a fixed end is
/// that line, so a good end point is a good start) and h = 1e-4 max(1, |x|_inf).
HimmelblauEstimate himmelblau_control(const HimmelblauControlProblem& problem, const Vec<2>& x,
                                      int k, int M, const Vec<2>& warm, const StreamKey& key);
/// As above, building the problem from `pb` first.
HimmelblauEstimate himmelblau_control(const HimmelblauProblem& pb, const Vec<2>& x, int k, int M,
                                      const Vec<2>& warm, const StreamKey& key);

/// One receding-horizon run: K steps from x0; noise from stream (seed, run, 0, kProcessNoise),
/// references from (seed, run, k, kReference).
struct HimmelblauRun {
  std::vector<Vec<2>> x;  ///< K + 1 states
  std::vector<Vec<2>> u;  ///< K controls
  double cost = 0.0;      ///< f(x_K) + sum_k R |u_k|^2 dt / 2
  double final_f = 0.0;   ///< f(x_K)
  double ess_mean = 0.0;
  int failed_minimizations = 0;
  Vec<2> last_noise = Vec<2>::Zero();  ///< W_{K-1}, the standard normal of the last step
  double max_laplace_gap = 0.0;  ///< max over steps and coordinates of |u_k - Laplace control|
};
HimmelblauRun simulate_himmelblau_run(const HimmelblauProblem& pb, int M, std::uint64_t seed,
                                      std::uint64_t run);

/// Closed-form expectations of the closed loop (the reference for spec §2.6 "Expected outcome").
///
/// Because gamma = sigma R is tiny, the weights are uniform to ~1e-6 and u_k equals the Laplace
/// control (z* - x_k)/(n dt) to ~1e-6, and z*(x_k) equals the minimiser x* of f up to
/// R |x_k - x*| / (n lambda_min(grad^2 f)) ~ 1e-5. With u_k = (x* - x_k)/(n dt) the error
/// e_k = x_k - x* obeys e_{k+1} = e_k (n-1)/n + sqrt(sigma dt) W_k, a discrete Brownian bridge:
///
///   e_k = e_0 n/K + sqrt(sigma dt) sum_{j<k} W_j n/(n_{j+1}),   n = K - k, n_j = K - j,
///   u_k dt = -e_0/K - sqrt(sigma dt) sum_{j<k} W_j / n_{j+1},
///
/// so x_{K-1} ~ N(x* + e_0/K, v I) with v = sigma dt sum_{i=1}^{K-1} 1/i^2, x_K ~ N(x*, sigma dt
/// I), and E|u_k dt|^2 = |e_0|^2/K^2 + 2 sigma dt sum_{j<k} 1/n_{j+1}^2. Expectations of the
/// quartic f under these Gaussians are exact by Gauss-Hermite quadrature. For the paper's
/// parameters: cost 1.02551, of which control 0.00241 and E f(x_K) = sigma dt tr(grad^2 f(x*))/2 +
/// 6 (sigma dt)^2 = 1.02310; E f(x_{K-1}) = 2.83775; sd of f(x_K) over runs 1.0738.
struct HimmelblauBridgeReference {
  Vec<2> minimizer = Vec<2>::Zero();  ///< x*, the minimum of f that the runs from x0 reach
  double control_cost = 0.0;          ///< E sum_k R |u_k|^2 dt / 2
  double final_f = 0.0;               ///< E f(x_K)
  double final_f_sd = 0.0;            ///< sd of f(x_K) (dominates the sd of the cost)
  double f_before_last_step = 0.0;    ///< E f(x_{K-1})
  double f_before_last_step_sd = 0.0;
  double cost() const { return control_cost + final_f; }
};
/// x* is the minimiser of f in the basin of z*(x0) (step 0 of the closed loop).
HimmelblauBridgeReference himmelblau_bridge_reference(const HimmelblauProblem& pb);

/// The run's cost with the uncontrollable last noise step replaced by its expectation:
///   cost - f(x* + sqrt(sigma dt) W_{K-1}) + E f(x* + sqrt(sigma dt) W)   (a control variate).
/// Same mean as `cost` up to sigma dt |grad^3 f| |z* - x*| ~ 1e-5, but an sd of ~1e-3 instead of
/// ~1.07: a 70-run mean then resolves the control part (0.0024) that the raw mean cannot.
double last_step_adjusted_cost(const HimmelblauProblem& pb, const HimmelblauRun& run,
                               const HimmelblauBridgeReference& ref);

}  // namespace implicit::control
