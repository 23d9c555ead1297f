// Partial noise (partial_noise.hpp, spec §2.2 "Partial noise"): the path integral over the noisy
// coordinates only. Oracles: the arm's closed form (joint_path_integral) and its LQR recursion,
// finite differences of F, and plain Monte Carlo over forward-Euler paths.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "implicit/control/controller.hpp"
#include "implicit/control/robot_arm.hpp"
#include "implicit/core/error.hpp"

namespace implicit::control {
namespace {

// Both joints of the arm in one problem (Dz = Dv = 2): psi is the product of the joints'.
struct TwoJointModel {
  Vec<2> target{1.0, -0.5};
  static constexpr bool kLinearQuadratic = true;
  template <typename T>
  Eigen::Matrix<T, 4, 1> drift(const Eigen::Matrix<T, 4, 1>& x, double) const {
    Eigen::Matrix<T, 4, 1> f;
    f << x(2), x(3), x(0) * 0.0, x(0) * 0.0;
    return f;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 4, 1>& x, double) const {
    return x(0) * 0.0;
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 4, 1>& x) const {
    const T e0 = x(0) - target(0), e1 = x(1) - target(1);
    return 0.5 * (e0 * e0 + e1 * e1 + x(2) * x(2) + x(3) * x(3));
  }
};

// A damped pendulum pushed by a torque: the angle integrates the velocity (affine, so the
// Hessian is exact), the velocity's drift and the running cost depend on the angle.
struct PendulumModel {
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double) const {
    using std::sin;
    return Eigen::Matrix<T, 2, 1>(x(1), -2.0 * sin(x(0)) - 0.3 * x(1));
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double t) const {
    using std::cos;
    return (1.0 + t) * (1.0 - cos(x(0))) + 0.1 * x(1) * x(1);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    return 0.5 * ((x(0) - 0.5) * (x(0) - 0.5) + x(1) * x(1));
  }
};

// Two noise-free coordinates with a nonlinear drift (a cart whose heading turns with the
// velocity): the gradient stays exact, the Hessian is Gauss-Newton.
struct HeadingModel {
  template <typename T>
  Eigen::Matrix<T, 3, 1> drift(const Eigen::Matrix<T, 3, 1>& x, double) const {
    using std::cos;
    using std::sin;
    Eigen::Matrix<T, 3, 1> f;
    f << x(2) * cos(x(1)), 0.5 * sin(x(2)), -x(0) * 0.4;
    return f;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 3, 1>& x, double) const {
    return 0.2 * x(0) * x(0) + 0.1 * x(1) * x(2);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 3, 1>& x) const {
    return 0.5 * ((x(0) - 1.0) * (x(0) - 1.0) + x(1) * x(1) + x(2) * x(2));
  }
};

ControlSpec<2, 1> pendulum_spec() {
  ControlSpec<2, 1> s;
  s.G << 0.0, 1.0;
  s.noise_covariance(0, 0) = 1.0;
  s.control_cost(0, 0) = 1.0;
  s.horizon = 1.0;
  s.dt = 0.05;
  return s;
}

TEST(PartialNoise, ArmJointLogPsiIsTheClosedForm) {
  const ArmProblem arm;  // explicit scheme, K = 200
  const int K = arm.num_steps();
  for (int joint = 0; joint < 2; ++joint) {
    const auto pj = arm_joint_problem(arm, joint);
    for (const auto& [k, z0, y0] : {std::tuple{0, 0.0, 0.0}, std::tuple{57, 0.4, -0.7},
                                    std::tuple{150, 1.1, 0.3}, std::tuple{199, 0.9, 0.05}}) {
      const auto exact = joint_path_integral(z0, y0, arm.target(joint), K - k, arm);
      const auto e = estimate_log_psi_implicit(pj, Vec<2>(z0, y0), k, 5, {1, 2, 3, 0});
      // Rounding only: F is quadratic, and both are its Laplace value.
      EXPECT_NEAR(e.log_psi, exact.log_psi, 1e-9 * (1.0 + std::abs(exact.log_psi)))
          << "joint " << joint << " k " << k;
      EXPECT_LT((e.minimizer - exact.mu).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

TEST(PartialNoise, TwoJointsAreTheProductOfOneJoint) {
  const ArmProblem arm;
  ControlSpec<4, 2> s;
  s.G.bottomRows<2>().setIdentity();
  s.noise_covariance = arm.sigma * Mat<2>::Identity();
  s.control_cost = arm.control_cost * Mat<2>::Identity();
  s.horizon = 0.5;
  s.dt = arm.dt;
  const ControlProblem<4, 2, TwoJointModel, 2> both(TwoJointModel{}, s);
  const Vec<4> x(0.2, -0.1, 0.5, 0.3);
  const int k = 10, n = both.num_steps() - k;
  const auto e = estimate_log_psi_implicit(both, x, k, 5, {1, 2, 3, 0});
  const double sum = joint_path_integral(x(0), x(2), 1.0, n, arm).log_psi +
                     joint_path_integral(x(1), x(3), -0.5, n, arm).log_psi;
  EXPECT_NEAR(e.log_psi, sum, 1e-9 * (1.0 + std::abs(sum)));
}

TEST(PartialNoise, ArmControlIsLqr) {
  const ArmProblem arm;
  const int K = arm.num_steps();
  EstimatorOptions o;
  o.samples = 1;
  for (int joint = 0; joint < 2; ++joint) {
    const auto pj = arm_joint_problem(arm, joint);
    const auto ric = joint_riccati(arm.target(joint), K, arm);
    for (const auto& [k, z0, y0] :
         {std::tuple{0, 0.0, 0.0}, std::tuple{80, 0.6, 1.2}, std::tuple{190, 0.95, -0.2}}) {
      const Vec<2> xj(z0, y0);
      const double lqr = -(ric.P[k] * xj + ric.q[k])(1) / arm.control_cost;
      const auto c = estimate_control(pj, xj, k, o, {1, static_cast<std::uint64_t>(k), 0, 0});
      // A central difference of log psi (exact up to rounding) with h = 1e-4: the rounding of
      // log psi, about 1e3 eps |log psi| <= 2e-11 here, divided by 2h, bounds the error by 1e-7.
      EXPECT_NEAR(c.u(0), lqr, 1e-7) << "joint " << joint << " k " << k;
      EXPECT_FALSE(c.fallback);
    }
  }
}

// The cart of docs/user-guide.md §5 is one arm joint with r = 0.1, tf = 1 and target 0: its
// control is discrete LQR's, -2.67510.
TEST(PartialNoise, UserGuideCartIsLqr) {
  ArmProblem cart;
  cart.control_cost = 0.1;
  cart.final_time = 1.0;
  cart.target.setZero();
  EstimatorOptions o;
  o.samples = 50;
  const auto c = estimate_control(arm_joint_problem(cart, 0), Vec<2>(1.0, 0.0), 0, o, {1, 0, 0, 0});
  const auto ric = joint_riccati(0.0, cart.num_steps(), cart);
  const double lqr = -(ric.P[0] * Vec<2>(1.0, 0.0) + ric.q[0])(1) / cart.control_cost;
  EXPECT_NEAR(c.u(0), lqr, 1e-7);
  EXPECT_NEAR(lqr, -2.67510, 5e-6);
}

TEST(PartialNoise, GenericArmSimulationMatchesTheClosedForm) {
  ArmProblem arm;
  arm.final_time = 0.5;
  const ArmParameters plant;
  const auto closed = simulate_arm(arm, plant, plant);
  const auto generic = simulate_arm(arm, plant, plant, 10, ArmController::kGeneric);
  EXPECT_LT(generic.lqr_max_abs_diff, 1e-7);
  for (std::size_t k = 0; k < closed.u.size(); ++k)
    EXPECT_LT((generic.u[k] - closed.u[k]).cwiseAbs().maxCoeff(), 1e-7) << k;
  arm.scheme = ArmScheme::kSemiImplicit;
  EXPECT_THROW(simulate_arm(arm, plant, plant, 10, ArmController::kGeneric), InvalidArgument);
}

// The noisy closed loop: the control at every visited state is LQR's (the noise enters the
// velocity only, through Sigma's root), and each step starts from the last minimiser's tail.
TEST(PartialNoise, ClosedLoopControlIsLqrAtEveryVisitedState) {
  ArmProblem arm;
  arm.final_time = 0.4;
  const int K = arm.num_steps();
  const auto pj = arm_joint_problem(arm, 1);
  const auto ric = joint_riccati(arm.target(1), K, arm);
  Eigen::MatrixXd noise(2, K);
  for (int k = 0; k < K; ++k) noise.col(k) << 10.0, std::sin(1.3 * k);  // no noise on the angle
  EstimatorOptions o;
  o.samples = 1;
  const auto run = simulate_closed_loop(pj, Vec<2>(0.1, -0.2), noise, o, 3);
  ASSERT_EQ(static_cast<int>(run.u.size()), K);
  for (int k = 0; k < K; ++k) {
    const Vec<2>& x = run.x[static_cast<std::size_t>(k)];
    EXPECT_NEAR(run.u[static_cast<std::size_t>(k)](0),
                -(ric.P[k] * x + ric.q[k])(1) / arm.control_cost, 1e-7)
        << k;
    // The angle moved by the drift alone: the angle's noise entry had no effect.
    EXPECT_DOUBLE_EQ(run.x[static_cast<std::size_t>(k) + 1](0), x(0) + arm.dt * x(1));
    EXPECT_EQ(run.psi[static_cast<std::size_t>(k)].minimizer.size(), K - k);
  }
}

// Central differences of F's gradient (and of the gradient for the Hessian), with the step and
// tolerance of a second-order difference: error h^2 |F'''| plus rounding eps |F| / h.
template <typename Problem>
void check_derivatives(const Problem& p, const Vec<Problem::kStateDim>& x, int k, bool hessian) {
  const auto F = p.path_function(x, k);
  const int N = F.dimension();
  Eigen::VectorXd y = p.drift_path(x, k);
  for (int i = 0; i < N; ++i) y(i) += 0.3 * std::sin(1.7 * i + 0.2);
  Eigen::VectorXd g;
  Eigen::MatrixXd H;
  const double f = F.evaluate(y, &g, &H);
  EXPECT_DOUBLE_EQ(f, F.evaluate(y, nullptr, nullptr));
  const double h = 1e-5;
  for (int i = 0; i < N; ++i) {
    Eigen::VectorXd yp = y, ym = y;
    yp(i) += h;
    ym(i) -= h;
    const double fd =
        (F.evaluate(yp, nullptr, nullptr) - F.evaluate(ym, nullptr, nullptr)) / (2 * h);
    EXPECT_NEAR(g(i), fd, 1e-6 * (1.0 + std::abs(f))) << "gradient " << i;
    if (!hessian) continue;
    Eigen::VectorXd gp, gm;
    F.evaluate(yp, &gp, nullptr);
    F.evaluate(ym, &gm, nullptr);
    const Eigen::VectorXd col = (gp - gm) / (2 * h);
    EXPECT_LT((H.col(i) - col).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + H.cwiseAbs().maxCoeff()))
        << "Hessian column " << i;
  }
  // The ray's slope against a central difference along a direction.
  Eigen::VectorXd d(N);
  for (int i = 0; i < N; ++i) d(i) = std::cos(0.9 * i);
  double slope = 0.0;
  const double fa = F.evaluate_along(y, d, 0.4, &slope);
  EXPECT_NEAR(fa, F.evaluate(y + 0.4 * d, nullptr, nullptr), 1e-12 * (1.0 + std::abs(fa)));
  const double fd =
      (F.evaluate_along(y, d, 0.4 + h, nullptr) - F.evaluate_along(y, d, 0.4 - h, nullptr)) /
      (2 * h);
  EXPECT_NEAR(slope, fd, 1e-6 * (1.0 + std::abs(fa)));
}

TEST(PartialNoise, PathFunctionDerivativesMatchFiniteDifferences) {
  const ControlProblem<2, 1, PendulumModel, 1> pendulum(PendulumModel{}, pendulum_spec());
  check_derivatives(pendulum, Vec<2>(0.3, -0.4), 3, true);  // affine f_z: exact Hessian
  ControlSpec<3, 1> s;
  s.G << 0.0, 0.0, 1.0;
  s.noise_covariance(0, 0) = 0.5;
  s.control_cost(0, 0) = 2.0;
  s.horizon = 0.6;
  s.dt = 0.05;
  const ControlProblem<3, 1, HeadingModel, 1> heading(HeadingModel{}, s);
  check_derivatives(heading, Vec<3>(0.2, 0.7, -0.3), 2, false);  // Gauss-Newton Hessian
}

// Implicit sampling (both maps) against plain Monte Carlo over forward-Euler paths: the same
// discretised psi, within 4.5 combined standard errors of log psi_hat.
TEST(PartialNoise, ImplicitSamplingAgreesWithMonteCarlo) {
  const ControlProblem<2, 1, PendulumModel, 1> p(PendulumModel{}, pendulum_spec());
  const auto mc = estimate_log_psi_monte_carlo(p, Vec<2>(0.8, -0.5), 4, 200000, {7, 0, 0, 0});
  for (SamplingMap map : {SamplingMap::kLinear, SamplingMap::kRandom}) {
    const auto is =
        estimate_log_psi_implicit(p, Vec<2>(0.8, -0.5), 4, 4000, {8, 0, 0, 0}, {}, {}, map);
    EXPECT_GT(is.ess, 0.5 * is.samples) << to_string(map);  // implicit sampling is efficient
    const double se = std::hypot(is.relative_se, mc.relative_se);
    EXPECT_NEAR(is.log_psi, mc.log_psi, 4.5 * se) << to_string(map);
    EXPECT_LT(se, 0.05);  // the comparison has power
  }
}

TEST(PartialNoise, RefusesWhatItCannotDo) {
  auto s = pendulum_spec();
  HardWall<2> wall;
  wall.time = 0.5;
  wall.openings = {{-1.0, 1.0}};
  EXPECT_THROW((ControlProblem<2, 1, PendulumModel, 1>(PendulumModel{}, s, {wall})),
               InvalidArgument);
  auto coarse = s;
  coarse.path_grid = PathGrid::kWallsAndHorizon;
  EXPECT_THROW((ControlProblem<2, 1, PendulumModel, 1>(PendulumModel{}, coarse)), InvalidArgument);
  auto pushed = s;
  pushed.G << 0.1, 1.0;  // the control moves the angle: not partial noise of the last coordinate
  EXPECT_THROW((ControlProblem<2, 1, PendulumModel, 1>(PendulumModel{}, pushed)), InvalidArgument);
  try {  // declared full noise on a singular Sigma: the message names the way out
    ControlProblem<2, 1, PendulumModel> full(PendulumModel{}, s);
    ADD_FAILURE() << "a singular Sigma was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("ControlProblem<D, P, Model, Dv>"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace implicit::control
