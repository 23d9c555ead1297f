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
// does not match); noise acting on a subspace only (Sigma singular: put the noise-free
// coordinates first and declare the number Dv of noisy ones, ControlProblem<D, P, Model, Dv>, as
// arm_joint_problem in robot_arm.hpp does; partial_noise.hpp); writing a hard wall as V = +inf in
// running_cost: that only zeroes weights, and with several openings the samples of one Laplace
// approximation rarely reach the other openings. Describe it as a HardWall instead: the estimator
// then finds one constrained minimum per opening and samples a mixture (spec §2.4.3). The random
// map needs F to increase along every ray from its minimiser ("star-shaped", e.g. convex F); with
// walls it runs inside each mode's openings, which is exact for a convex F.
//
// The pieces, one header each: problem.hpp (ControlSpec, HardWall, ControlProblem),
// path_function.hpp (F and its derivatives), partial_noise.hpp (F over the noisy coordinates
// when the noise acts on some only), path_solvers.hpp (constrained Newton, the random
// map's ray equation), wall_modes.hpp (the modes of hard walls), wall_mixture.hpp (the mixture
// over them), wall_values.hpp (linear-quadratic models: only the wall values are drawn),
// estimators.hpp (log psi by implicit sampling or plain Monte Carlo), controller.hpp (the control
// and the closed loop).

#include "implicit/control/controller.hpp"
#include "implicit/control/estimators.hpp"
#include "implicit/control/path_function.hpp"
#include "implicit/control/problem.hpp"
