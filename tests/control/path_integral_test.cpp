// The generic path integral control problem and estimators (spec §2.1-2.3).
#include <gtest/gtest.h>

#include <cmath>

#include "implicit/control/himmelblau.hpp"
#include "implicit/control/path_integral.hpp"
#include "implicit/core/error.hpp"

using namespace implicit::control;
using implicit::Mat;
using implicit::Vec;

namespace {

// Free walker with a quadratic final cost: the double slit after its wall.
struct FreeWalker {
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

// Ornstein-Uhlenbeck drift, quadratic running and final costs: F is quadratic.
struct LinearQuadratic {
  template <typename T>
  Eigen::Matrix<T, 1, 1> drift(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return -1.0 * x;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return 0.5 * x(0) * x(0);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 1, 1>& x) const {
    return 1.5 * (x(0) - 1.0) * (x(0) - 1.0);
  }
};

struct Himmelblau2 {
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

ControlSpec<1, 1> scalar_spec(double sigma, double r, double horizon, double dt) {
  ControlSpec<1, 1> s;
  s.G << 1.0;
  s.noise_covariance << sigma;
  s.control_cost << r;
  s.horizon = horizon;
  s.dt = dt;
  return s;
}

}  // namespace

TEST(ControlSpec, ConditionEightAndBadInput) {
  EXPECT_NEAR(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.02)), 0.1, 1e-15);
  // Two controls: R = diag(1, 2) with Q Q^T = I violates (8) (gamma would differ per axis).
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.control_cost << 1, 0, 0, 2;
  try {
    check_control_spec(s);
    FAIL() << "expected InvalidArgument";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("condition (8)"), std::string::npos) << e.what();
  }
  s.control_cost.setIdentity();
  s.noise_covariance << 1, 0, 0, -1;  // not positive semi-definite
  EXPECT_THROW(check_control_spec(s), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.0)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, -0.1)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.03)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, -0.1, 2.0, 0.02)), implicit::InvalidArgument);
  // Partial noise (noise on the velocity only): Sigma singular, a clear error.
  ControlSpec<2, 1> arm;
  arm.G << 0, 1;
  arm.noise_covariance << 1;
  arm.control_cost << 0.01;
  try {
    check_control_spec(arm);
    FAIL() << "expected InvalidArgument";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
}

TEST(PathIntegral, ExactForQuadraticFAnyM) {
  // After the double slit's wall: log psi = 1/2 log(g/(g + s n dt)) - x^2/(2(g + s n dt)).
  ControlProblem problem(FreeWalker{}, scalar_spec(1.0, 0.1, 1.0, 0.02));
  for (int M : {1, 7}) {
    for (int k : {0, 30, 49}) {
      const Vec<1> x(0.7);
      const auto e = estimate_log_psi_implicit(problem, x, k, M, {5});
      const double spread = 0.1 + (50 - k) * 0.02;
      EXPECT_NEAR(e.log_psi, 0.5 * std::log(0.1 / spread) - 0.49 / (2 * spread), 1e-10);
      EXPECT_NEAR(e.ess, M, 1e-9);
      const auto c = estimate_control(problem, x, k, {.samples = M}, {5});
      EXPECT_NEAR(c.u(0), -0.7 / spread, 1e-7);
    }
  }
}

TEST(PathIntegral, BandedHessianMatchesFiniteDifferences) {
  ControlProblem problem(LinearQuadratic{}, scalar_spec(0.5, 2.0, 1.0, 0.1));
  const auto F = problem.path_function(Vec<1>(0.3), 0);
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(10, -0.5, 0.8), g, gp, gm;
  implicit::BlockTridiagonal<1> H;
  F.evaluate(y, &g, &H);
  const Eigen::MatrixXd Hd = H.to_dense();
  for (int i = 0; i < 10; ++i) {
    Eigen::VectorXd yp = y, ym = y;
    yp(i) += 1e-6;
    ym(i) -= 1e-6;
    EXPECT_NEAR(g(i), (F.evaluate(yp, nullptr, nullptr) - F.evaluate(ym, nullptr, nullptr)) / 2e-6,
                1e-6 * (1 + std::abs(g(i))));
    F.evaluate(yp, &gp, nullptr);
    F.evaluate(ym, &gm, nullptr);
    const Eigen::VectorXd col = (gp - gm) / 2e-6;
    EXPECT_LT((col - Hd.col(i)).cwiseAbs().maxCoeff(), 1e-6 * (1 + Hd.cwiseAbs().maxCoeff()));
  }
}

TEST(PathIntegral, ImplicitAgreesWithPlainMonteCarlo) {
  // F is quadratic (linear drift, quadratic costs), so implicit sampling is exact (equal
  // weights); plain Monte Carlo is unbiased for psi. Tolerance: 4.5 SE of log psi_hat_MC, the
  // SE taken from its weights (relative sd / sqrt(M)).
  ControlProblem problem(LinearQuadratic{}, scalar_spec(0.5, 2.0, 1.0, 0.05));
  EXPECT_NEAR(problem.gamma(), 1.0, 1e-15);
  const Vec<1> x(0.4);
  const auto imp = estimate_log_psi_implicit(problem, x, 0, 20, {9});
  EXPECT_NEAR(imp.ess, 20.0, 1e-9);
  const auto mc = estimate_log_psi_monte_carlo(problem, x, 0, 20000, {9});
  EXPECT_NEAR(mc.log_psi, imp.log_psi, 4.5 * mc.relative_se);
  EXPECT_GT(mc.relative_se, 0.0);
}

TEST(PathIntegral, HimmelblauThroughTheGenericProblem) {
  // The generic banded path (2x2 blocks, autodiff) reproduces the specialised Himmelblau code.
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.noise_covariance = 0.01 * Mat<2>::Identity();
  s.control_cost = 0.01 * Mat<2>::Identity();
  s.horizon = 20.0;
  s.dt = 1.0;
  ControlProblem problem(Himmelblau2{}, s);
  EXPECT_NEAR(problem.gamma(), 1e-4, 1e-18);
  const Vec<2> x0(-1, -4);
  const auto c = estimate_control(problem, x0, 0, {.samples = 50}, {3});
  ASSERT_EQ(c.worst_status, implicit::MinimizeStatus::kConverged);
  EXPECT_NEAR(c.u(0), -0.1389649, 1e-6);
  EXPECT_NEAR(c.u(1), 0.0358407, 1e-6);
  EXPECT_NEAR(c.psi.minimizer(38), -3.77929836, 1e-7);
  EXPECT_NEAR(c.psi.minimizer(39), -3.28318625, 1e-7);
  EXPECT_GT(c.psi.ess, 45.0);
}

TEST(PathIntegral, ClosedLoopTakesTheNoiseAsInput) {
  ControlProblem problem(FreeWalker{}, scalar_spec(1.0, 0.1, 1.0, 0.02));
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(1, 50);
  const auto r = simulate_closed_loop(problem, Vec<1>(1.0), zero, {.samples = 3}, 1);
  ASSERT_EQ(r.x.size(), 51u);
  // Noise-free LQ: x_{k+1} = x_k (1 - dt/(g + s (tf - t_k))).
  double x = 1.0;
  for (int k = 0; k < 50; ++k) x *= 1.0 - 0.02 / (0.1 + (50 - k) * 0.02);
  EXPECT_NEAR(r.x.back()(0), x, 1e-7);
  EXPECT_THROW(simulate_closed_loop(problem, Vec<1>(1.0), Eigen::MatrixXd::Zero(1, 3), {}, 1),
               implicit::InvalidArgument);
}
