// The Lorenz models: RK4's order of accuracy, Lorenz-96's energy identity and symmetries, and
// the tangent-linear derivative of the k-step map against central finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/da/lorenz.hpp"
#include "implicit/da/model.hpp"

namespace implicit::da {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

Vec<3> l63_after(double t, double dt) {
  Vec<3> x(1.509, -1.531, 25.46);
  Lorenz63{}.steps(x, dt, static_cast<int>(std::lround(t / dt)));
  return x;
}

// RK4 has global error C dt^4 + O(dt^5), so halving dt divides the error by 16 (1 + O(dt)).
// The reference is RK4 with dt / 64: its own error is 64^-4 = 6e-8 of the coarse run's, far
// below the band. The band 16 +- 1.6 allows the O(dt) correction (|J| dt ~ 0.04 at dt = 0.0025,
// the tendency Jacobian's norm on the attractor being ~15) times a constant up to 2.5; a
// first- or second-order scheme would give 2 or 4 and a wrong stage weight 8 or less.
TEST(Lorenz63, Rk4ErrorFallsSixteenfoldWhenTheStepHalves) {
  const double t = 0.5, dt = 0.005;
  const Vec<3> reference = l63_after(t, dt / 64.0);
  const double e1 = (l63_after(t, dt) - reference).norm();
  const double e2 = (l63_after(t, dt / 2.0) - reference).norm();
  ASSERT_GT(e2, 1e3 * kEps * reference.norm());  // well above round-off
  EXPECT_NEAR(e1 / e2, 16.0, 1.6) << "e(dt) = " << e1 << ", e(dt/2) = " << e2;
}

TEST(Lorenz96, Rk4ErrorFallsSixteenfoldWhenTheStepHalves) {
  const Lorenz96 l(10, 8.0);
  Lorenz96::Workspace w(10);
  auto after = [&](double dt) {
    Eigen::VectorXd x = Eigen::VectorXd::Constant(10, 8.0);
    x(0) += 1.0;
    x(3) -= 0.5;
    l.steps(x, dt, static_cast<int>(std::lround(1.0 / dt)), w);
    return x;
  };
  // As for Lorenz-63: the error ratio is 16 (1 + O(dt)); here |J| dt ~ 0.1 at dt = 0.005.
  const Eigen::VectorXd reference = after(0.01 / 64.0);
  const double e1 = (after(0.01) - reference).norm();
  const double e2 = (after(0.005) - reference).norm();
  ASSERT_GT(e2, 1e3 * kEps * reference.norm());
  EXPECT_NEAR(e1 / e2, 16.0, 1.6) << "e(dt) = " << e1 << ", e(dt/2) = " << e2;
}

// The advection (x_{i+1} - x_{i-2}) x_{i-1} conserves the energy |x|^2 / 2, so
// x . f(x) = -|x|^2 + F sum(x) exactly; round-off is a few ulps of the terms' size.
TEST(Lorenz96, AdvectionConservesEnergy) {
  for (int n : {4, 5, 10, 40}) {
    const Lorenz96 l(n, 8.0);
    Eigen::VectorXd x(n), f(n);
    for (int i = 0; i < n; ++i) x(i) = std::sin(1.7 * i + 0.3) * 5.0 + 1.0;
    l.tendency(x, f);
    const double expected = -x.squaredNorm() + 8.0 * x.sum();
    const double scale = x.cwiseAbs().maxCoeff();
    EXPECT_NEAR(x.dot(f), expected, 64.0 * n * kEps * scale * scale * scale) << "n = " << n;
  }
}

TEST(Lorenz96, UniformForcingIsAFixedPointAndStepsCommuteWithShifts) {
  const int n = 12;
  const Lorenz96 l(n, 8.0);
  Lorenz96::Workspace w(n);
  Eigen::VectorXd fixed = Eigen::VectorXd::Constant(n, 8.0);
  l.steps(fixed, 0.05, 10, w);
  EXPECT_EQ((fixed - Eigen::VectorXd::Constant(n, 8.0)).cwiseAbs().maxCoeff(), 0.0);

  Eigen::VectorXd x(n), shifted(n);
  for (int i = 0; i < n; ++i) x(i) = std::cos(0.9 * i) * 3.0 + 2.0;
  for (int i = 0; i < n; ++i) shifted((i + 3) % n) = x(i);
  l.steps(x, 0.05, 7, w);
  l.steps(shifted, 0.05, 7, w);
  for (int i = 0; i < n; ++i) EXPECT_EQ(shifted((i + 3) % n), x(i)) << "i = " << i;
}

// Central differences D(h) have truncation error ~ c h^2 and round-off ~ eps |M| / h. The
// truncation part is measured by Richardson: D(h) - D(h/2) = (3/4) c h^2 + ..., so the error of
// D(h/2) is about |D(h) - D(h/2)| / 3. The tolerance is four times that plus 100 times the
// round-off bound; a wrong derivative is off by O(|J|), orders of magnitude more.
template <typename Map, typename Jac>
void expect_jacobian_matches_central_differences(const Map& map, const Eigen::VectorXd& x0,
                                                 const Jac& jacobian, double h) {
  const int n = static_cast<int>(x0.size());
  const double size = map(x0).cwiseAbs().maxCoeff();
  for (int j = 0; j < n; ++j) {
    auto central = [&](double step) {
      Eigen::VectorXd plus = x0, minus = x0;
      plus(j) += step;
      minus(j) -= step;
      return Eigen::VectorXd((map(plus) - map(minus)) / (2.0 * step));
    };
    const Eigen::VectorXd d1 = central(h), d2 = central(h / 2.0);
    for (int i = 0; i < n; ++i) {
      const double tol = 4.0 * std::abs(d1(i) - d2(i)) / 3.0 + 100.0 * kEps * size / (h / 2.0);
      EXPECT_NEAR(jacobian(i, j), d2(i), tol) << "entry (" << i << ", " << j << ")";
    }
  }
}

TEST(Lorenz63, TangentLinearMatchesCentralDifferences) {
  const Lorenz63 l;
  Vec<3> x(1.509, -1.531, 25.46);
  Mat<3> j;
  Vec<3> end = x;
  l.steps(end, 0.01, 25, &j);
  auto map = [&](const Eigen::VectorXd& v) {
    Vec<3> y = v;
    l.steps(y, 0.01, 25);
    return Eigen::VectorXd(y);
  };
  EXPECT_EQ((end - map(x)).cwiseAbs().maxCoeff(), 0.0);  // same trajectory with and without J
  expect_jacobian_matches_central_differences(map, x, j, 1e-4);
}

TEST(Lorenz96, TangentLinearMatchesCentralDifferences) {
  const int n = 10;
  const Lorenz96 l(n, 8.0);
  Lorenz96::Workspace w(n);
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x(i) = std::sin(2.1 * i) * 4.0 + 2.0;
  Eigen::VectorXd end = x;
  Eigen::MatrixXd j;
  l.steps(end, 0.05, 5, w, &j);
  auto map = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd y = v;
    l.steps(y, 0.05, 5, w);
    return y;
  };
  EXPECT_EQ((end - map(x)).cwiseAbs().maxCoeff(), 0.0);
  expect_jacobian_matches_central_differences(map, x, j, 1e-4);
}

TEST(Lorenz96, RefusesBadSettings) {
  EXPECT_THROW(Lorenz96(3, 8.0), InvalidArgument);
  EXPECT_THROW(Lorenz96(10, std::nan("")), InvalidArgument);
  EXPECT_THROW(Lorenz96Model(Lorenz96(10, 8.0), 0.0, 1), InvalidArgument);
  EXPECT_THROW(Lorenz63Model(Lorenz63{}, 0.01, 0), InvalidArgument);
  try {
    Lorenz96(2, 8.0);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4, got 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace implicit::da
