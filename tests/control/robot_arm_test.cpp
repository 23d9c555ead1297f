// Robot arm (spec §2.5): dynamics oracles, path integral = LQR, closed-loop oracles.
#include <gtest/gtest.h>

#include <cmath>

#include "implicit/control/robot_arm.hpp"
#include "implicit/core/error.hpp"

using namespace implicit::control;
using implicit::Mat;
using implicit::Vec;

TEST(ArmDynamics, Oracles) {
  // Spec §2.5.7 at theta = (0.4, 0.7), theta' = (0.3, -0.5).
  ArmParameters p;
  EXPECT_DOUBLE_EQ(p.a1(), 5.5);
  EXPECT_DOUBLE_EQ(p.a2(), 2.25);
  EXPECT_DOUBLE_EQ(p.a3(), 0.5);
  const Vec<2> th(0.4, 0.7), thd(0.3, -0.5);
  const Mat<2> M = arm_mass_matrix(p, th), C = arm_coriolis_matrix(p, th, thd);
  EXPECT_NEAR(M(0, 0), 6.2648421873, 1e-9);
  EXPECT_NEAR(M(0, 1), 2.6324210936, 1e-9);
  EXPECT_NEAR(M(1, 0), 2.6324210936, 1e-9);
  EXPECT_NEAR(M(1, 1), 2.25, 1e-12);
  EXPECT_NEAR(C(0, 0), 0.1610544218, 1e-9);
  EXPECT_NEAR(C(0, 1), 0.0644217687, 1e-9);
  EXPECT_NEAR(C(1, 0), 0.0966326531, 1e-9);
  EXPECT_EQ(C(1, 1), 0.0);
  // M' = dM/dtheta2 theta2' must make M' - 2C skew-symmetric (passivity of the arm).
  const double h = 1e-6;
  const Mat<2> Mdot = (arm_mass_matrix(p, th + Vec<2>(0, h) * thd(1) / 1.0) -
                       arm_mass_matrix(p, th - Vec<2>(0, h) * thd(1) / 1.0)) /
                      (2 * h);
  const Mat<2> S = Mdot - 2 * C;
  EXPECT_NEAR(S(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(S(1, 1), 0.0, 1e-9);
  EXPECT_NEAR(S(0, 1), 0.0322108844, 1e-9);
  EXPECT_NEAR(S(1, 0), -0.0322108844, 1e-9);
  const Vec<2> u(1, -2);
  const Vec<2> tau = arm_inverse_dynamics(p, th, thd, u);
  EXPECT_NEAR(tau(0), 1.0161054422, 1e-9);
  EXPECT_NEAR(tau(1), -1.8385891104, 1e-9);
  ArmParameters wrong;
  wrong.m1 = 1.4;
  EXPECT_NEAR(wrong.a1(), 5.6, 1e-15);
  const Vec<2> tau_w = arm_inverse_dynamics(wrong, th, thd, u);
  EXPECT_NEAR(tau_w(0), 1.1161054422, 1e-9);
  EXPECT_NEAR(tau_w(1), -1.8385891104, 1e-9);
  const Vec<2> acc = arm_acceleration(p, th, thd, tau_w);
  EXPECT_NEAR(acc(0), 1.0313971563, 1e-9);
  EXPECT_NEAR(acc(1), -2.0367335717, 1e-9);
  // With exact parameters inverse dynamics linearises: theta'' = u.
  EXPECT_NEAR((arm_acceleration(p, th, thd, tau) - u).norm(), 0.0, 1e-12);
}

TEST(ArmDynamics, KineticEnergyConservedWithoutTorque) {
  ArmParameters p;
  Vec<4> s(0.4, 0.7, 0.3, -0.5);
  auto energy = [&](const Vec<4>& x) {
    return 0.5 * x.tail<2>().dot(arm_mass_matrix(p, x.head<2>()) * x.tail<2>());
  };
  EXPECT_NEAR(energy(s), 0.168304734381, 1e-11);
  const double e0 = energy(s);
  for (int i = 0; i < 5000; ++i) s = arm_rk4_step(p, s, Vec<2>::Zero(), 1e-3);
  EXPECT_NEAR(energy(s), e0, 1e-12);
}

TEST(ArmPathIntegral, OneJointOracles) {
  // Spec §2.5.5: (z0, y0) = (0.2, 0.3), theta* = 1, n = 200, r = 0.01, sigma = 1, dt = 0.01.
  ArmProblem pr;
  const auto e = joint_path_integral(0.2, 0.3, 1.0, 200, pr);
  EXPECT_NEAR(e.phi, 0.202303192989, 1e-11);
  EXPECT_NEAR(e.log_det_L, 465.283182344, 1e-9);
  EXPECT_NEAR(e.log_psi, -4.96846693783, 1e-9);
  EXPECT_NEAR(pr.gamma() * e.phi, 0.00202303192989, 1e-13);
  EXPECT_NEAR(e.u, 0.581932896431, 1e-11);
  EXPECT_NEAR(e.final_angle, 0.9927601718, 1e-9);
  const auto ric = joint_riccati(1.0, 200, pr);
  EXPECT_NEAR(ric.control(0, Vec<2>(0.2, 0.3)), 0.574693068245, 1e-11);

  ArmProblem semi = pr;
  semi.scheme = ArmScheme::kSemiImplicit;
  const auto s = joint_path_integral(0.2, 0.3, 1.0, 200, semi);
  EXPECT_NEAR(s.phi, 0.204418058245, 1e-11);
  EXPECT_NEAR(s.log_det_L, 465.283327264, 1e-9);
  EXPECT_NEAR(s.log_psi, -4.97072672359, 1e-9);
  EXPECT_NEAR(s.u, 0.578866262832, 1e-11);
  EXPECT_NEAR(s.final_angle, 0.9927188001, 1e-9);
  EXPECT_NEAR(joint_riccati(1.0, 200, semi).control(0, Vec<2>(0.2, 0.3)), s.u, 1e-12);
}

TEST(ArmPathIntegral, ControlVersusTimeStep) {
  // Spec §2.5.5: u_PI (explicit scheme) and u_LQR,0 for several dt, horizon 2 s.
  struct Row {
    double dt, u_pi, u_lqr;
  };
  for (const Row& r :
       {Row{0.1, 0.5964503928, 0.5257491999}, Row{0.02, 0.5834870046, 0.5690477019},
        Row{0.005, 0.5811610830, 0.5775360614}, Row{0.001, 0.5805461217, 0.5798202940}}) {
    ArmProblem pr;
    pr.dt = r.dt;
    const int n = pr.num_steps();
    EXPECT_NEAR(joint_path_integral(0.2, 0.3, 1.0, n, pr).u, r.u_pi, 1e-9) << "dt " << r.dt;
    EXPECT_NEAR(joint_riccati(1.0, n, pr).control(0, Vec<2>(0.2, 0.3)), r.u_lqr, 1e-9);
  }
}

TEST(ArmPathIntegral, EqualsLqrValueGradientAndEnvelopeRelation) {
  // u_PI = -(1/r)[P_0 x + q_0]_y and u_PI = u_LQR,0 - (dt/r)(z*_n - theta*) (spec §2.5.3),
  // and u = sigma d/dy0 log psi by finite differences.
  ArmProblem pr;
  const int n = 200;
  const auto ric = joint_riccati(1.0, n, pr);
  for (double z0 : {-0.3, 0.2, 1.4}) {
    for (double y0 : {-1.0, 0.3, 2.0}) {
      const auto e = joint_path_integral(z0, y0, 1.0, n, pr);
      const Vec<2> x(z0, y0);
      EXPECT_NEAR(e.u, -(ric.P[0] * x + ric.q[0])(1) / pr.control_cost, 1e-9);
      EXPECT_NEAR(e.u, ric.control(0, x) - pr.dt / pr.control_cost * (e.final_angle - 1.0), 1e-9);
      const double h = 1e-5;
      const double fd = (joint_path_integral(z0, y0 + h, 1.0, n, pr).log_psi -
                         joint_path_integral(z0, y0 - h, 1.0, n, pr).log_psi) /
                        (2 * h);
      EXPECT_NEAR(e.u, pr.sigma * fd, 1e-6);
    }
  }
}

TEST(ArmPathIntegral, FullArmFromRest) {
  ArmProblem pr;
  const Vec<2> u = arm_path_integral_control(Vec<4>::Zero(), 200, pr);
  EXPECT_NEAR(u(0), 1.471156278104, 1e-11);
  EXPECT_NEAR(u(1), -0.735578139052, 1e-11);
  const auto j1 = joint_path_integral(0, 0, 1.0, 200, pr);
  const auto j2 = joint_path_integral(0, 0, -0.5, 200, pr);
  EXPECT_NEAR(j1.phi, 0.728331063791, 1e-11);
  EXPECT_NEAR(j2.phi, 0.182082765948, 1e-11);
  EXPECT_NEAR(j1.log_psi, -5.494494808635, 1e-9);
  EXPECT_NEAR(j2.log_psi, -4.948246510792, 1e-9);
  EXPECT_NEAR(j1.log_psi + j2.log_psi, -10.442741319427, 1e-9);
}

TEST(ArmClosedLoop, Oracles) {
  // Spec §2.5.6: nonlinear plant, RK4 with 10 substeps, no noise.
  ArmProblem pr;
  ArmParameters plant, wrong;
  wrong.m1 = 1.4;
  const auto exact = simulate_arm(pr, plant, plant);
  const auto& xe = exact.x.back();
  EXPECT_NEAR(xe(0), 0.984639108688, 1e-9);
  EXPECT_NEAR(xe(1), -0.492338853898, 1e-9);
  EXPECT_NEAR(xe(2), 0.014909390290, 1e-9);
  EXPECT_NEAR(xe(3), -0.007463351561, 1e-9);
  EXPECT_NEAR(exact.tau[0](0), 7.539675925288, 1e-9);
  EXPECT_NEAR(exact.tau[0](1), 2.390628951921, 1e-9);
  EXPECT_LT(exact.lqr_max_abs_diff, 1e-9);
  const auto w = simulate_arm(pr, plant, wrong);
  const auto& xw = w.x.back();
  EXPECT_NEAR(xw(0), 0.983143660935, 1e-9);
  EXPECT_NEAR(xw(1), -0.490551932647, 1e-9);
  EXPECT_NEAR(xw(2), 0.013266534369, 1e-9);
  EXPECT_NEAR(xw(3), -0.005492061589, 1e-9);
  EXPECT_NEAR(w.tau[0](0), 7.686791553099, 1e-9);
  EXPECT_NEAR(w.tau[0](1), 2.390628951921, 1e-9);
  EXPECT_NEAR(exact.final_angle_error, std::hypot(1 - 0.984639108688, -0.5 + 0.492338853898), 1e-9);
}

TEST(ArmClosedLoop, SemiImplicitSchemeEqualsLqrFeedback) {
  ArmProblem pr;
  pr.scheme = ArmScheme::kSemiImplicit;
  const auto sim = simulate_arm(pr, ArmParameters{}, ArmParameters{});
  EXPECT_LT(sim.lqr_max_abs_diff, 1e-9);
}

TEST(ArmProblem, BadInput) {
  ArmProblem pr;
  pr.dt = 0.0;
  EXPECT_THROW(pr.validate(), implicit::InvalidArgument);
  pr = {};
  pr.dt = 0.03;
  EXPECT_THROW(pr.validate(), implicit::InvalidArgument);
  pr = {};
  pr.sigma = -1.0;
  EXPECT_THROW(pr.validate(), implicit::InvalidArgument);
  ArmParameters p;
  p.m1 = 0.0;
  EXPECT_THROW(simulate_arm(ArmProblem{}, p, ArmParameters{}), implicit::InvalidArgument);
  EXPECT_THROW(joint_path_integral(0, 0, 1, 0, ArmProblem{}), implicit::InvalidArgument);
}
