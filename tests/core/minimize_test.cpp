// The damped Newton minimiser: convergence, indefinite Hessians, non-finite F, statuses.
//
// Tolerances. At convergence max|grad F| <= 1e-10 (the default gradient tolerance); near a
// minimum with Hessian H, |x - x*| <= |H^{-1}| |grad F|, so 1e-8 on x covers H^{-1} up to 100.
// F values are compared to 1e-12 (quadratic convergence gives F - F* ~ |grad|^2 / eigenvalue).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/oracle_models.hpp"
#include "implicit/implicit.hpp"

namespace implicit {
namespace {

struct Rosenbrock {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    const auto a = 1.0 - x(0);
    const auto b = x(1) - x(0) * x(0);
    return a * a + 100.0 * (b * b);
  }
};

TEST(Minimize, Rosenbrock) {
  const auto f = make_autodiff_target<2>(Rosenbrock{});
  const auto r = minimize(f, Vec<2>(-1.2, 1.0));
  EXPECT_EQ(r.status, MinimizeStatus::kConverged) << to_string(r.status);
  // The Hessian at (1, 1) has condition number ~2500 (smallest eigenvalue 0.4), so
  // |x - x*| <= 2.5 |grad| <= 2.5e-10.
  EXPECT_LT((r.x - Vec<2>(1.0, 1.0)).norm(), 1e-8);
  EXPECT_LT(r.value, 1e-18);
  EXPECT_LT(r.iterations, 50);
}

TEST(Minimize, RosenbrockDynamicSize) {
  const auto f = make_autodiff_target<Eigen::Dynamic>(Rosenbrock{}, 2);
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;
  const auto r = minimize(f, x0);
  EXPECT_EQ(r.status, MinimizeStatus::kConverged);
  EXPECT_LT((r.x - Eigen::Vector2d(1.0, 1.0)).norm(), 1e-8);
}

TEST(Minimize, IterationLimitIsReported) {
  const auto f = make_autodiff_target<2>(Rosenbrock{});
  MinimizeOptions o;
  o.max_iterations = 3;
  const auto r = minimize(f, Vec<2>(-1.2, 1.0), o);
  EXPECT_EQ(r.status, MinimizeStatus::kMaxIterations);
  EXPECT_EQ(r.iterations, 3);
  EXPECT_TRUE(std::isfinite(r.value));
}

// Double well F = (x1^2 - 1)^2 + x2^2 / 2: saddle at 0, minima at (+-1, 0) with H = diag(8, 1).
struct DoubleWell {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    const auto a = x(0) * x(0) - 1.0;
    return a * a + 0.5 * (x(1) * x(1));
  }
};

TEST(Minimize, IndefiniteStartReachesMinimum) {
  // At x1 = 0.05 the Hessian has d2F/dx1^2 = 12 x1^2 - 4 < 0: the plain Newton step would go
  // uphill towards the saddle; Levenberg damping must turn it into descent.
  const auto f = make_autodiff_target<2>(DoubleWell{});
  const auto r = minimize(f, Vec<2>(0.05, 0.3));
  EXPECT_EQ(r.status, MinimizeStatus::kConverged) << to_string(r.status);
  EXPECT_NEAR(std::abs(r.x(0)), 1.0, 1e-8);
  EXPECT_NEAR(r.x(1), 0.0, 1e-8);
  EXPECT_NEAR(r.value, 0.0, 1e-12);
  EXPECT_NEAR(r.hessian(0, 0), 8.0, 1e-6);
}

TEST(Minimize, SaddleWithZeroGradientIsNotPositiveDefinite) {
  // Started exactly on the saddle the gradient is zero, so Newton stops at once; the status
  // must say that the point is not a minimum.
  const auto f = make_autodiff_target<2>(DoubleWell{});
  const auto r = minimize(f, Vec<2>(0.0, 0.0));
  EXPECT_EQ(r.status, MinimizeStatus::kNotPositiveDefinite) << to_string(r.status);
  EXPECT_FALSE(r.converged());
}

TEST(Minimize, FlatQuarticMinimum) {
  // F = x^4: H(0) = 0. Newton converges linearly (x <- 2x/3) until 4|x|^3 <= 1e-10, i.e.
  // |x| <= 3e-4, where H = 12 x^2 > 0: "converged" is the sensible answer, with |x| < 1e-3.
  const auto f =
      make_autodiff_target<1>([](const auto& x) { return (x(0) * x(0)) * (x(0) * x(0)); });
  const auto r = minimize(f, Vec<1>(1.0));
  EXPECT_EQ(r.status, MinimizeStatus::kConverged) << to_string(r.status);
  EXPECT_LT(std::abs(r.x(0)), 1e-3);
  EXPECT_GE(r.hessian(0, 0), 0.0);
}

TEST(Minimize, NaNStartIsNonFinite) {
  const auto f = make_autodiff_target<2>(Rosenbrock{});
  const auto r = minimize(f, Vec<2>(std::numeric_limits<double>::quiet_NaN(), 1.0));
  EXPECT_EQ(r.status, MinimizeStatus::kNonFinite);
}

TEST(Minimize, NaNObjectiveIsNonFinite) {
  const auto f = make_analytic_target<1>([](const Vec<1>&, Vec<1>* g, Mat<1>* h) {
    if (g) (*g)(0) = 0.0;
    if (h) (*h)(0, 0) = 1.0;
    return std::numeric_limits<double>::quiet_NaN();
  });
  EXPECT_EQ(minimize(f, Vec<1>(0.0)).status, MinimizeStatus::kNonFinite);
}

TEST(Minimize, InfiniteStartIsNonFinite) {
  // T5 has F = +inf for x1 <= 0: starting there is reported, not thrown.
  const auto f = make_autodiff_target<2>(testing::T5Model{});
  EXPECT_EQ(minimize(f, Vec<2>(-1.0, 0.0)).status, MinimizeStatus::kNonFinite);
}

// T5 mode oracle (spec §1.6): mu = (4, 0), H = diag(1/4, 1/2), phi = 4 - 4 log 4 + 2 log 2.
void expect_t5_mode(const MinimizeResult<2>& r) {
  EXPECT_EQ(r.status, MinimizeStatus::kConverged) << to_string(r.status);
  // |x - mu| <= |H^{-1}| |grad| = 4e-10.
  EXPECT_NEAR(r.x(0), 4.0, 1e-8);
  EXPECT_NEAR(r.x(1), 0.0, 1e-8);
  EXPECT_NEAR(r.value, 4.0 - 4.0 * std::log(4.0) + 2.0 * std::log(2.0), 1e-12);
  EXPECT_NEAR(r.value, -0.1588831, 5e-8);  // the spec's 7-digit value
  EXPECT_NEAR(r.hessian(0, 0), 0.25, 1e-8);
  EXPECT_NEAR(r.hessian(1, 1), 0.5, 1e-8);
  EXPECT_NEAR(r.hessian(0, 1), 0.0, 1e-12);
}

TEST(Minimize, T5ModeFromInside) {
  const auto f = make_autodiff_target<2>(testing::T5Model{});
  expect_t5_mode(minimize(f, Vec<2>(1.0, 1.0)));
}

TEST(Minimize, T5ModeAvoidsInfiniteRegion) {
  // From x1 = 20 the Newton step in x1 is -(1 - 4/20) / (4/400) = -80, landing at x1 = -60 where
  // F = +inf: the line search must back off into the support instead of failing.
  const auto f = make_autodiff_target<2>(testing::T5Model{});
  const auto r = minimize(f, Vec<2>(20.0, 3.0));
  expect_t5_mode(r);
  EXPECT_GT(r.evaluations, r.iterations + 1);  // some trial points were rejected
}

TEST(Minimize, UnboundedBelowDoesNotHang) {
  // F = -x is unbounded: every step decreases F; the minimiser stops at the iteration limit.
  const auto f = make_autodiff_target<1>([](const auto& x) { return -x(0); });
  const auto r = minimize(f, Vec<1>(0.0));
  EXPECT_FALSE(r.converged());
}

}  // namespace
}  // namespace implicit
