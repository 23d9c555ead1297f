#pragma once
// Path integral control of a two-link planar robot arm (paper §3.2, Table 3, Figure 4; spec
// §2.5).
//
// The arm M(theta) theta'' + C(theta, theta') theta' = tau is linearised by inverse dynamics,
// tau = M_hat u + C_hat theta' (hats: the controller's possibly wrong parameters), so that with
// exact parameters theta'' = u. The controller solves the stochastic linear problem
// d theta = theta' dt, d theta' = u dt + q dW with cost E[|theta(tf) - theta*|^2/2 +
// |theta'(tf)|^2/2 + integral r|u|^2/2] by path integral control. Noise acts on velocities only
// (partial noise), so the path integral runs over the velocity path y_1..y_n of each joint; F is
// quadratic, psi is exact without sampling, and the control equals discrete LQR (spec §2.5.3),
// which the tests check to machine precision. Each joint is also a generic ControlProblem with
// partial noise (arm_joint_problem), which the library's estimator solves with the same F
// (`implicit arm` runs Figure 4 that way); the closed form here is its independent check.
//
//   implicit::control::ArmProblem arm;                          // spec §2.5.4 parameters
//   auto j = implicit::control::joint_path_integral(0.2, 0.3, 1.0, 200, arm);  // one joint
//   j.u;        // 0.581932896431 (explicit scheme)
//   auto sim = implicit::control::simulate_arm(arm, ArmParameters{}, ArmParameters{});
//   auto same = implicit::control::simulate_arm(arm, ArmParameters{}, ArmParameters{}, 10,
//                                               ArmController::kGeneric);  // to 1e-7 in u
//
// Common mistakes (spec E17-E19): the paper's M11 = a1 + a3 cos(theta2) is not a two-link arm's
// (use a1 + 2 a3 cos(theta2)); inverse dynamics needs C(theta, theta') theta' (C is a matrix);
// and gamma = r q^2, not r, for velocity noise q dW.

#include <vector>

#include <Eigen/Core>

#include "implicit/control/problem.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// Physical parameters of the arm (Table 3 of the paper; SI units).
struct ArmParameters {
  double l1 = 1.0;   ///< length of link 1 [m]
  double lc1 = 0.5;  ///< distance from joint 1 to the centre of mass of link 1 [m]
  double lc2 = 0.5;  ///< distance from joint 2 to the centre of mass of link 2 [m]
  double m1 = 1.0;   ///< mass of link 1 [kg]
  double m2 = 1.0;   ///< mass of link 2 [kg]
  double I1 = 2.0;   ///< moment of inertia of link 1 [kg m^2]
  double I2 = 2.0;   ///< moment of inertia of link 2 [kg m^2]

  double a1() const { return I1 + I2 + m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2); }
  double a2() const { return I2 + m2 * lc2 * lc2; }
  double a3() const { return m2 * l1 * lc2; }
  /// Throws InvalidArgument for non-positive masses, lengths or inertias.
  void validate() const;
};

/// Mass matrix M(theta) (symmetric positive definite).
Mat<2> arm_mass_matrix(const ArmParameters& p, const Vec<2>& theta);
/// Coriolis/centrifugal matrix C(theta, theta'), with M' - 2C skew-symmetric.
Mat<2> arm_coriolis_matrix(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot);
/// Inverse dynamics tau = M(theta) u + C(theta, theta') theta'.
Vec<2> arm_inverse_dynamics(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot,
                            const Vec<2>& u);
/// Forward dynamics theta'' = M^{-1} (tau - C theta') (Cholesky solve).
Vec<2> arm_acceleration(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot,
                        const Vec<2>& tau);
/// One RK4 step of length h for the state (theta, theta') with the torque held constant.
Vec<4> arm_rk4_step(const ArmParameters& p, const Vec<4>& state, const Vec<2>& tau, double h);

/// Discretisation of the angle in the velocity path (spec §2.5.2-2.5.3).
enum class ArmScheme {
  kExplicit,      ///< z_{i+1} = z_i + dt y_i (the paper's): u_PI = u_LQR + O(dt)
  kSemiImplicit,  ///< z_{i+1} = z_i + dt y_{i+1}: u_PI equals the first LQR control exactly
};

/// The controller's stochastic linear problem (spec §2.5.4: the paper gives no theta*, tf, r).
struct ArmProblem {
  double control_cost = 0.01;             ///< r, R = r I
  double sigma = 1.0;                     ///< q^2: velocity noise variance rate
  double final_time = 2.0;                ///< tf [s]
  double dt = 0.01;                       ///< time step [s]
  Vec<2> target{1.0, -0.5};               ///< theta* [rad]
  Vec<4> initial_state = Vec<4>::Zero();  ///< (theta, theta') at t = 0
  ArmScheme scheme = ArmScheme::kExplicit;

  double gamma() const { return control_cost * sigma; }  ///< condition (8): gamma = r q^2
  int num_steps() const;  ///< tf / dt; throws unless it is a positive integer
  void validate() const;
};

/// Path integral of one joint from (angle z0, velocity y0) over n steps (spec §2.5.2).
struct JointPathIntegral {
  Eigen::VectorXd mu;        ///< minimiser y_1..y_n of F
  double phi = 0.0;          ///< F(mu)
  double log_det_L = 0.0;    ///< 1/2 log det of the Hessian of F
  double log_psi = 0.0;      ///< -phi - (n/2) log(sigma dt) - log det L (exact: F is quadratic)
  double u = 0.0;            ///< gamma/r d/dy0 log psi, by the envelope theorem
  double final_angle = 0.0;  ///< z_n(mu)
};

/// F is minimised in O(n) with the tridiagonal Cholesky plus a rank-one (Sherman-Morrison)
/// correction for the angle term, and log det with the matrix determinant lemma.
JointPathIntegral joint_path_integral(double z0, double y0, double target, int n,
                                      const ArmProblem& problem);

/// Path integral control of both joints at state x = (theta, theta') with n steps to go.
Vec<2> arm_path_integral_control(const Vec<4>& x, int n, const ArmProblem& problem);

/// Discrete LQR for one joint (spec §2.5.3): value function V_i(x) = x^T P_i x / 2 + q_i^T x +
/// const and feedback u_i = -K_i x - k_i for i = 0..n-1 (index i = steps already taken).
struct JointRiccati {
  std::vector<Mat<2>> P;              ///< n + 1 matrices
  std::vector<Vec<2>> q;              ///< n + 1 vectors
  std::vector<Eigen::RowVector2d> K;  ///< n gains
  std::vector<double> k;              ///< n offsets
  double control(int i, const Vec<2>& x) const { return -(K[i] * x)(0) - k[i]; }
};
JointRiccati joint_riccati(double target, int n, const ArmProblem& problem);

/// One joint after inverse dynamics as a generic control problem with partial noise (state
/// (angle, velocity), noise and control on the velocity): d z = v dt, d v = u dt + q dW, no
/// running cost, final cost ((z - target)^2 + v^2) / 2. Its path function is exactly the one
/// joint_path_integral minimises in closed form (explicit scheme).
struct ArmJointModel {
  double target = 0.0;  ///< theta* of this joint [rad]
  static constexpr bool kLinearQuadratic = true;
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return Eigen::Matrix<T, 2, 1>(x(1), x(1) * 0.0);
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return x(0) * 0.0;
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    const T e = x(0) - target;
    return 0.5 * (e * e + x(1) * x(1));
  }
};
using ArmJointProblem = ControlProblem<2, 1, ArmJointModel, 1>;

/// Joint `joint` (0 or 1) of `problem` as a generic problem: G = (0, 1)^T, Q Q^T = q^2, R = r,
/// horizon tf, step dt. Throws InvalidArgument for a bad problem or joint, and for the
/// semi-implicit scheme, which is not a forward-Euler path.
ArmJointProblem arm_joint_problem(const ArmProblem& problem, int joint);

/// Which estimator gives the arm's control.
enum class ArmController {
  kClosedForm,  ///< joint_path_integral: O(n) per joint (the default)
  kGeneric,     ///< estimate_control on arm_joint_problem (partial noise, dense factor)
};

/// One closed-loop simulation of spec §2.5.6 (no noise, RK4 plant with 10 substeps).
struct ArmSimulation {
  std::vector<double> t;           ///< K + 1 times
  std::vector<Vec<4>> x;           ///< K + 1 states (theta, theta')
  std::vector<Vec<2>> u;           ///< K controls
  std::vector<Vec<2>> tau;         ///< K torques
  double lqr_max_abs_diff = 0.0;   ///< max |u_PI - (-(1/r)[P_k x + q_k]_velocity)| over steps
  double final_angle_error = 0.0;  ///< |theta(tf) - theta*|
};
/// `plant`: the true arm; `model`: the controller's parameters for inverse dynamics.
/// `controller`: kGeneric needs the explicit scheme.
ArmSimulation simulate_arm(const ArmProblem& problem, const ArmParameters& plant,
                           const ArmParameters& model, int substeps = 10,
                           ArmController controller = ArmController::kClosedForm);

}  // namespace implicit::control
