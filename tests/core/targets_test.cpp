// Targets: one model, three derivative strategies (analytic, automatic, numeric), and the
// derivative checker.
//
// Tolerances. Analytic vs automatic: both are exact formulas evaluated in double precision, so
// they agree to round-off, ~1e-15 relative; we allow 1e-12 (relative to 1 + |entry|). Numeric:
// central differences with h = eps^(1/3) for the gradient have truncation h^2 |F'''|/6 ~ 1e-11
// plus round-off eps |F| / h ~ 1e-11, so 1e-8 is safe; the Hessian from values with
// h = eps^(1/4) has truncation h^2 |F''''| / 12 ~ 1e-9 and round-off eps |F| / h^2 ~ 1e-8 |F|,
// so 1e-6 (the derivatives here are O(1) and |F| < 10).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "implicit/implicit.hpp"

namespace implicit {
namespace {

using ::testing::HasSubstr;

// A model that exercises atan2, log1p, exp, sqrt and division:
//   F(x) = log1p(x0^2) + exp(0.3 x2) + sqrt(1 + x0^2 + x1^2) + x0 / (2 + x1^2) + atan2(x1, x2 + 3).
struct Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    using std::atan2;
    using std::exp;
    using std::log1p;
    using std::sqrt;
    return log1p(x(0) * x(0)) + exp(0.3 * x(2)) + sqrt(1.0 + x(0) * x(0) + x(1) * x(1)) +
           x(0) / (2.0 + x(1) * x(1)) + atan2(x(1), x(2) + 3.0);
  }
};

// The same F with hand-derived gradient and Hessian, term by term.
double model_analytic(const Eigen::Vector3d& x, Eigen::Vector3d* grad, Eigen::Matrix3d* hess) {
  const double x0 = x(0), x1 = x(1), x2 = x(2);
  const double p = 1.0 + x0 * x0;       // log1p(x0^2) = log p
  const double e = std::exp(0.3 * x2);  // exp(0.3 x2)
  const double c = std::sqrt(1.0 + x0 * x0 + x1 * x1);
  const double q = 2.0 + x1 * x1;                   // x0 / q
  const double y = x2 + 3.0, r2 = x1 * x1 + y * y;  // atan2(x1, y)
  if (grad) {
    (*grad)(0) = 2.0 * x0 / p + x0 / c + 1.0 / q;
    (*grad)(1) = x1 / c - 2.0 * x0 * x1 / (q * q) + y / r2;
    (*grad)(2) = 0.3 * e - x1 / r2;
  }
  if (hess) {
    const double c3 = c * c * c, r4 = r2 * r2;
    Eigen::Matrix3d& h = *hess;
    h(0, 0) = (2.0 - 2.0 * x0 * x0) / (p * p) + 1.0 / c - x0 * x0 / c3;
    h(1, 1) =
        1.0 / c - x1 * x1 / c3 - 2.0 * x0 * (q - 4.0 * x1 * x1) / (q * q * q) - 2.0 * x1 * y / r4;
    h(2, 2) = 0.09 * e + 2.0 * x1 * y / r4;
    h(0, 1) = h(1, 0) = -x0 * x1 / c3 - 2.0 * x1 / (q * q);
    h(0, 2) = h(2, 0) = 0.0;
    h(1, 2) = h(2, 1) = (x1 * x1 - y * y) / r4;
  }
  return std::log1p(x0 * x0) + e + c + x0 / q + std::atan2(x1, y);
}

std::vector<Eigen::Vector3d> test_points() {
  std::vector<Eigen::Vector3d> points = {{0.0, 0.0, 0.0}, {0.7, -1.3, 0.4}, {-2.0, 0.5, -1.0}};
  Rng rng({.seed = 11, .step = 0, .index = 0, .purpose = purpose::kUser});
  for (int k = 0; k < 5; ++k) points.push_back(rng.normal_vector<3>());
  return points;
}

TEST(Targets, AnalyticMatchesAutomatic) {
  const auto analytic = make_analytic_target<3>(model_analytic);
  for (const auto& x : test_points()) {
    const DerivativeCheck c = check_derivatives(analytic, Model{}, x);
    EXPECT_TRUE(c.ok(1e-12)) << "at " << x.transpose() << ": " << c.describe();
  }
}

TEST(Targets, NumericMatchesAutomatic) {
  const auto numeric = make_numeric_target<3>([](const Eigen::Vector3d& x) { return Model{}(x); });
  const auto automatic = make_autodiff_target<3>(Model{});
  for (const auto& x : test_points()) {
    Eigen::Vector3d gn, ga;
    Eigen::Matrix3d hn, ha;
    const double fn = numeric.evaluate(x, &gn, &hn);
    const double fa = automatic.evaluate(x, &ga, &ha);
    EXPECT_EQ(fn, fa);
    EXPECT_LT((gn - ga).cwiseAbs().maxCoeff(), 1e-8) << "at " << x.transpose();
    EXPECT_LT((hn - ha).cwiseAbs().maxCoeff(), 1e-6) << "at " << x.transpose();
    // The checker reaches the same verdict from the numeric target's side.
    EXPECT_TRUE(check_derivatives(numeric, Model{}, x).ok(1e-6));
  }
}

TEST(Targets, ValueOnlyCallsAgree) {
  // A value-only call runs the model on doubles; it must equal the jet's value bit for bit
  // except for association order, so 1e-15 relative.
  const auto automatic = make_autodiff_target<3>(Model{});
  for (const auto& x : test_points()) {
    Eigen::Vector3d g;
    const double with_grad = automatic.evaluate(x, &g, nullptr);
    EXPECT_NEAR(automatic.evaluate(x, nullptr, nullptr), with_grad, 1e-15 * std::abs(with_grad));
  }
}

TEST(Targets, CheckerNamesWrongHessianEntry) {
  // Deliberately wrong analytic Hessian: entry (1, 2) off by 0.5 (and only that entry, so the
  // worst entry is unambiguous).
  const auto wrong =
      make_analytic_target<3>([](const Eigen::Vector3d& x, Eigen::Vector3d* g, Eigen::Matrix3d* h) {
        const double f = model_analytic(x, g, h);
        if (h) (*h)(1, 2) += 0.5;
        return f;
      });
  const Eigen::Vector3d x(0.7, -1.3, 0.4);
  const DerivativeCheck c = check_derivatives(wrong, Model{}, x);
  EXPECT_FALSE(c.ok(1e-6));
  EXPECT_EQ(c.hessian_row, 1);
  EXPECT_EQ(c.hessian_col, 2);
  EXPECT_LT(c.gradient_error, 1e-12);
  EXPECT_THAT(c.describe(), HasSubstr("worst Hessian entry (1, 2)"));
}

TEST(Targets, CheckerNamesWrongGradientEntryAndNaN) {
  const auto wrong =
      make_analytic_target<3>([](const Eigen::Vector3d& x, Eigen::Vector3d* g, Eigen::Matrix3d* h) {
        const double f = model_analytic(x, g, h);
        if (g) (*g)(2) = std::numeric_limits<double>::quiet_NaN();
        return f;
      });
  const DerivativeCheck c = check_derivatives(wrong, Model{}, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_FALSE(c.ok(1.0));  // a NaN entry fails any tolerance
  EXPECT_EQ(c.gradient_index, 2);
  EXPECT_THAT(c.describe(), HasSubstr("worst gradient entry 2"));
}

TEST(Targets, CheckerReportsEntriesAnAnalyticFunctorForgets) {
  // A dynamic-size analytic functor that fills only the diagonal of the Hessian: the checker
  // pre-fills with NaN, so the forgotten off-diagonal entries are reported, not read as garbage.
  const auto partial = make_analytic_target<Eigen::Dynamic>(
      [](const Eigen::VectorXd& x, Eigen::VectorXd* g, Eigen::MatrixXd* h) {
        if (g) *g = x;
        if (h)
          for (Eigen::Index i = 0; i < x.size(); ++i) (*h)(i, i) = 1.0;
        return 0.5 * x.squaredNorm() + x(0) * x(1);
      },
      2);
  const DerivativeCheck c = check_derivatives(
      partial, [](const auto& x) { return 0.5 * (x(0) * x(0) + x(1) * x(1)) + x(0) * x(1); },
      Eigen::VectorXd::Ones(2));
  EXPECT_FALSE(c.ok(1.0));
  EXPECT_NE(c.hessian_row, c.hessian_col);  // an off-diagonal entry
}

TEST(Targets, DynamicSizeMatchesFixedSize) {
  // The same model with run-time dimension: values and derivatives identical to the fixed one
  // up to round-off (different summation order inside Eigen is allowed: 1e-13).
  const auto fixed = make_autodiff_target<3>(Model{});
  const auto dynamic = make_autodiff_target<Eigen::Dynamic>(Model{}, 3);
  const auto numeric =
      make_numeric_target<Eigen::Dynamic>([](const Eigen::VectorXd& x) { return Model{}(x); }, 3);
  EXPECT_EQ(dynamic.dim(), 3);
  for (const auto& x3 : test_points()) {
    const Eigen::VectorXd x = x3;
    Eigen::Vector3d gf;
    Eigen::Matrix3d hf;
    Eigen::VectorXd gd, gn;
    Eigen::MatrixXd hd, hn;
    const double ff = fixed.evaluate(x3, &gf, &hf);
    const double fd = dynamic.evaluate(x, &gd, &hd);
    numeric.evaluate(x, &gn, &hn);
    EXPECT_NEAR(ff, fd, 1e-13);
    EXPECT_LT((gd - gf).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_LT((hd - hf).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_LT((gn - gf).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT((hn - hf).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_TRUE(check_derivatives(dynamic, Model{}, x).ok(1e-13));
  }
}

TEST(Targets, DynamicJetConstantsAdoptSize) {
  // A model that starts from a constant (size-0 jet for Eigen::Dynamic) and a functor that
  // ignores x entirely: both must give correctly sized derivatives.
  const auto sum_sq = make_autodiff_target<Eigen::Dynamic>(
      [](const auto& x) {
        using S = typename std::decay_t<decltype(x)>::Scalar;
        S s(1.0);
        for (Eigen::Index i = 0; i < x.size(); ++i) s += x(i) * x(i);
        return s;
      },
      4);
  Eigen::VectorXd g;
  Eigen::MatrixXd h;
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(4, -1.0, 2.0);
  EXPECT_DOUBLE_EQ(sum_sq.evaluate(x, &g, &h), 1.0 + x.squaredNorm());
  EXPECT_LT((g - 2.0 * x).norm(), 1e-15);
  EXPECT_LT((h - 2.0 * Eigen::MatrixXd::Identity(4, 4)).norm(), 1e-15);

  const auto constant = make_autodiff_target<Eigen::Dynamic>(
      [](const auto& x) {
        using S = typename std::decay_t<decltype(x)>::Scalar;
        return S(3.0);
      },
      2);
  EXPECT_EQ(constant.evaluate(Eigen::VectorXd::Ones(2), &g, &h), 3.0);
  EXPECT_EQ(g, Eigen::VectorXd::Zero(2));
  EXPECT_EQ(h, Eigen::MatrixXd::Zero(2, 2));
}

TEST(Targets, JetElementaryFunctions) {
  // Each elementary function of the jet against its closed-form first and second derivative.
  const double a = 0.37;
  auto check = [a](auto f, double d1, double d2) {
    const auto j = f(Jet2<1>::variable(a, 0));
    EXPECT_NEAR(j.g(0), d1, 1e-14 * (1.0 + std::abs(d1)));
    EXPECT_NEAR(j.h(0, 0), d2, 1e-14 * (1.0 + std::abs(d2)));
  };
  check([](const Jet2<1>& x) { return sin(x); }, std::cos(a), -std::sin(a));
  check([](const Jet2<1>& x) { return cos(x); }, -std::sin(a), -std::cos(a));
  check([](const Jet2<1>& x) { return tan(x); }, 1.0 / std::pow(std::cos(a), 2),
        2.0 * std::tan(a) / std::pow(std::cos(a), 2));
  check([](const Jet2<1>& x) { return atan(x); }, 1.0 / (1.0 + a * a),
        -2.0 * a / std::pow(1.0 + a * a, 2));
  check([](const Jet2<1>& x) { return tanh(x); }, 1.0 - std::pow(std::tanh(a), 2),
        -2.0 * std::tanh(a) * (1.0 - std::pow(std::tanh(a), 2)));
  check([](const Jet2<1>& x) { return pow(x, 2.5); }, 2.5 * std::pow(a, 1.5),
        3.75 * std::pow(a, 0.5));
  check([](const Jet2<1>& x) { return log(x); }, 1.0 / a, -1.0 / (a * a));
  check([](const Jet2<1>& x) { return 2.0 / x; }, -2.0 / (a * a), 4.0 / (a * a * a));
  check([](const Jet2<1>& x) { return atan2(2.0, x); }, -2.0 / (4.0 + a * a),
        4.0 * a / std::pow(4.0 + a * a, 2));
}

}  // namespace
}  // namespace implicit
