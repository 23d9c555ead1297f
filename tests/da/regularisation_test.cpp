// The particle filters' covariance-scaled regularisation: the kernel width, the weighted
// covariance and its guarded factor, the covariance the regularised ensemble gets, determinism
// and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/filters.hpp"
#include "implicit/da/twin.hpp"
#include "refusal.hpp"

namespace implicit::da {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd reg_a() {
  MatrixXd a(3, 3);
  a << 0.9, 0.2, 0.0, -0.1, 0.8, 0.1, 0.0, 0.3, 0.7;
  return a;
}
MatrixXd reg_cov() {  // anisotropic and correlated: an isotropic jitter would not match it
  MatrixXd p(3, 3);
  p << 2.0, 0.6, 0.1, 0.6, 0.5, -0.2, 0.1, -0.2, 1.2;
  return p;
}
Problem reg_problem(double r_scale) {  // deterministic linear model, observe components 0 and 2
  MatrixXd h = MatrixXd::Zero(2, 3);
  h(0, 0) = 1.0;
  h(1, 2) = 1.0;
  return {std::make_shared<LinearModel>(reg_a()), h, r_scale * MatrixXd::Identity(2, 2),
          MatrixXd()};
}

MatrixXd gaussian_members(int count, const MatrixXd& cov, std::uint64_t seed) {
  const MatrixXd l = cov.llt().matrixL();
  MatrixXd e(3, count);
  VectorXd z(3);
  for (int j = 0; j < count; ++j) {
    Rng rng({seed, 0, static_cast<std::uint64_t>(j), purpose::kInitial});
    rng.fill_normal(z);
    e.col(j) = l * z;
  }
  return e;
}

MatrixXd cov_over_n(const MatrixXd& e) {  // 1/N normalisation, as the equal-weight C
  const MatrixXd d = e.colwise() - e.rowwise().mean();
  return d * d.transpose() / static_cast<double>(e.cols());
}

TEST(Regularisation, SilvermanBandwidthInOneDimensionIsTheRuleOfThumb) {
  // n = 1: h = (4 / (3 N))^(1/5) = 1.0592 N^(-1/5), Silverman's "1.06 sigma N^(-1/5)".
  for (int m : {10, 100, 800})
    EXPECT_NEAR(silverman_bandwidth(m, 1) * std::pow(m, 0.2), 1.0592, 5e-5) << m;
  EXPECT_LT(silverman_bandwidth(800, 10), silverman_bandwidth(100, 10));
}

TEST(Regularisation, WeightedCovarianceMatchesTheDefinition) {
  // Two members x0 = (0, 0), x1 = (1, 2) with weights 1/4, 3/4: mean (3/4, 3/2), and
  // C = w0 w1 (x1 - x0)(x1 - x0)^T = 3/16 [[1, 2], [2, 4]].
  const std::vector<VectorXd> xs = {VectorXd{{0.0, 0.0}}, VectorXd{{1.0, 2.0}}};
  const std::vector<double> w = {0.25, 0.75};
  MatrixXd c;
  weighted_covariance(xs, w, c);
  MatrixXd expected(2, 2);
  expected << 1.0, 2.0, 2.0, 4.0;
  expected *= 3.0 / 16.0;
  EXPECT_LT((c - expected).cwiseAbs().maxCoeff(), 1e-15);
  // Rank 1: no Cholesky factor without the ridge, which is 1e-10 times the mean variance
  // (15/32) times a power of 10, and the factor reproduces C + ridge I.
  MatrixXd l;
  const double ridge = covariance_factor(c, l);
  EXPECT_GT(ridge, 0.0);
  EXPECT_LE(ridge, 1e-6);
  EXPECT_LT((l * l.transpose() - c - ridge * MatrixXd::Identity(2, 2)).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_EQ(covariance_factor(expected + MatrixXd::Identity(2, 2), l), 0.0);
  EXPECT_GT(covariance_factor(MatrixXd::Zero(2, 2), l), 0.0);  // collapsed: ridge 1e-12 I
  EXPECT_TRUE(l.allFinite());
}

// A bootstrap cycle with R = 1e6 I leaves the weights equal to 1/N within a relative ~1e-6: N_eff
// falls short of N by a relative ~1e-12 (so threshold 1 resamples; with R = 1e12 I it would round
// to N and nothing would be resampled), and systematic resampling keeps every member exactly once
// unless the cumulative weight's drift from j/N (~1e-6 sqrt(N), under 1e-4) straddles the uniform.
// The population is then regularised: the members are f_j + e_j, f_j = A x_j, e_j = s L xi_j with
// s = jitter h and L L^T = C, the covariance of the f_j. Conditional on the f_j (centred, 1/N
// covariance C) the ensemble's 1/N covariance is
//   C + (1/N) sum_j (f_j e_j^T + e_j f_j^T) + (1/N) sum_j e_j e_j^T - ebar ebar^T,
// whose entry (a, b) has mean (1 + s^2) C_ab + O(s^2 C / N) and variance
//   (2 s^2 + s^4) (C_aa C_bb + C_ab^2) / N
// (the cross term contributes 2 s^2 (C_aa C_bb + C_ab^2) / N, the noise term s^4 (...) / N, and
// they are uncorrelated: odd moments of xi vanish). Each entry is checked within 4 standard
// errors; the O(s^2 C / N) bias is 1/sqrt(N) of one standard error.
TEST(Regularisation, CovarianceRegularisedEnsembleHasInflatedCovariance) {
  const int count = 4000;
  const double jitter = 2.0;
  const MatrixXd x = gaussian_members(count, reg_cov(), 5);
  EnsembleFilter f(reg_problem(1e6), {.method = Method::kBootstrap,
                                      .members = count,
                                      .jitter = jitter,
                                      .regularisation = Regularisation::kCovariance,
                                      .resample_threshold = 1.0,
                                      .seed = 9});
  f.initialize(x);
  const auto& a = f.assimilate(VectorXd{{0.3, -0.4}});
  ASSERT_TRUE(a.resampled);
  const MatrixXd c = cov_over_n(reg_a() * x);
  const MatrixXd got = cov_over_n(f.members());
  const double s = jitter * silverman_bandwidth(count, 3);
  const double s2 = s * s;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const double se = std::sqrt((2.0 * s2 + s2 * s2) * (c(i, i) * c(k, k) + c(i, k) * c(i, k)) /
                                  static_cast<double>(count));
      EXPECT_NEAR(got(i, k), (1.0 + s2) * c(i, k), 4.0 * se) << i << ", " << k;
    }
}

TEST(Regularisation, SameSeedSameNumbersForAnyThreadCount) {
  for (Method m : {Method::kBootstrap, Method::kImplicit}) {
    TwinSettings s{.cycles = 5,
                   .interval = 1.0,
                   .truth0 = VectorXd{{1.0, -0.5, 2.0}},
                   .mean0 = VectorXd{{1.0, -0.5, 2.0}},
                   .cov0 = reg_cov(),
                   .seed = 11,
                   .keep_history = true};
    const FilterOptions o{.method = m,
                          .members = 200,
                          .jitter = 0.5,
                          .regularisation = Regularisation::kCovariance,
                          .resample_threshold = 0.9};
    TwinResult one, two;
    {
      ThreadLimit limit(1);
      one = run_twin(reg_problem(0.5), o, s);
    }
    {
      ThreadLimit limit(2);
      two = run_twin(reg_problem(0.5), o, s);
    }
    EXPECT_GT(one.resamplings, 0) << to_string(m);
    for (std::size_t k = 0; k < one.means.size(); ++k)
      EXPECT_EQ((one.means[k] - two.means[k]).cwiseAbs().maxCoeff(), 0.0) << to_string(m);
    EXPECT_EQ(one.rmse_a, two.rmse_a);
  }
}

using implicit::test_support::expect_refused;

TEST(Regularisation, RefusesBadInput) {
  const Problem p = reg_problem(0.5);
  const auto cov = Regularisation::kCovariance;
  expect_refused([&] { EnsembleFilter(p, {.jitter = -0.1, .regularisation = cov}); },
                 "jitter std >= 0, got -0.1");
  expect_refused([&] { EnsembleFilter(p, {.method = Method::kImplicit, .regularisation = cov}); },
                 "expected a jitter > 0");
  expect_refused([] { parse_regularisation("shrink"); }, "expected iso or cov, got 'shrink'");
  EXPECT_EQ(parse_regularisation("cov"), cov);
  expect_refused([] { silverman_bandwidth(0, 3); }, "N >= 1");
  MatrixXd c;
  expect_refused(
      [&] {
        weighted_covariance(std::vector<VectorXd>{VectorXd::Zero(2)}, std::vector<double>{}, c);
      },
      "one weight per member");
  MatrixXd l;
  expect_refused([&] { covariance_factor(MatrixXd::Constant(2, 2, std::nan("")), l); },
                 "not finite");
}

}  // namespace
}  // namespace implicit::da
