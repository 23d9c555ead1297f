// Bad input: every misuse gives a clear InvalidArgument naming what was expected and what was
// given, or (for algorithm outcomes) a status; never a crash, a hang or a silent NaN.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "implicit/implicit.hpp"

namespace implicit {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Quadratic {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    typename V::Scalar s(0.0);
    for (Eigen::Index i = 0; i < x.size(); ++i) s += 0.5 * (x(i) * x(i));
    return s;
  }
};

// The message of the InvalidArgument thrown by `f` ("<no exception>" if none, "<other: ...>" if
// another type was thrown).
std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("<other: ") + e.what() + ">";
  }
  return "<no exception>";
}

struct Case {
  const char* what;
  std::function<void()> call;
  const char* expected_message;  // a substring of the InvalidArgument's message
};

TEST(BadInput, ThrowsWithClearMessage) {
  const Mat<2> indefinite = (Mat<2>() << 1.0, 0.0, 0.0, -1.0).finished();
  const auto f3 = make_autodiff_target<Eigen::Dynamic>(Quadratic{}, 3);
  const auto nan_target = make_autodiff_target<2>([](const auto& x) { return x(0) * kNaN; });
  const auto saddle = make_autodiff_target<2>([](const auto& x) { return x(0) * x(1); });
  std::vector<double> out(4);
  const std::vector<Case> cases = {
      {"zero dimension, autodiff", [] { make_autodiff_target<Eigen::Dynamic>(Quadratic{}, 0); },
       "target dimension: expected a positive number, got 0"},
      {"zero dimension, analytic",
       [] {
         make_analytic_target<Eigen::Dynamic>(
             [](const Eigen::VectorXd&, Eigen::VectorXd*, Eigen::MatrixXd*) { return 0.0; }, 0);
       },
       "expected a positive number, got 0"},
      {"negative dimension, numeric",
       [] { make_numeric_target<Eigen::Dynamic>([](const Eigen::VectorXd&) { return 0.0; }, -2); },
       "expected a positive number, got -2"},
      {"non-PD Hessian at the minimum", [&] { Laplace<2>::make(Vec<2>::Zero(), 0.0, indefinite); },
       "positive definite"},
      {"NaN Hessian", [&] { Laplace<2>::make(Vec<2>::Zero(), 0.0, Mat<2>::Constant(kNaN)); },
       "positive definite"},
      {"non-finite phi", [&] { Laplace<2>::make(Vec<2>::Zero(), kInf, Mat<2>::Identity()); },
       "expected a finite F(mu), got inf"},
      {"Hessian of the wrong size",
       [&] {
         Laplace<Eigen::Dynamic>::make(Eigen::VectorXd::Zero(3), 0.0,
                                       Eigen::MatrixXd::Identity(2, 2));
       },
       "expected a 3x3 Hessian, got 2x2"},
      {"NaN in F: sampling reports the minimiser status",
       [&] { sample(nan_target, Vec<2>(1.0, 1.0), 10, {.seed = 1}); },
       "minimising F failed with status 'non_finite'"},
      {"saddle: sampling reports the minimiser status",
       [&] { sample(saddle, Vec<2>(0.0, 0.0), 10, {.seed = 1}); },
       "status 'not_positive_definite'"},
      {"start point of the wrong dimension",
       [&] { sample(f3, Eigen::VectorXd::Zero(2), 10, {.seed = 1}); },
       "start point has dimension 2, expected 3"},
      {"minimiser start point of the wrong dimension",
       [&] { minimize(f3, Eigen::VectorXd::Zero(4)); },
       "minimize: expected a start point of dimension 3, got 4"},
      {"derivative check at a point of the wrong dimension",
       [&] { check_derivatives(f3, Quadratic{}, Eigen::VectorXd::Zero(2)); },
       "check_derivatives: expected a point of dimension 3, got 2"},
      {"zero samples", [&] { sample(f3, Eigen::VectorXd::Zero(3), 0, {.seed = 1}); },
       "expected at least one sample, got 0"},
      {"NaN log-weight",
       [&] {
         normalize_log_weights(std::vector<double>{0.0, 1.0, kNaN, 2.0}, out);
       },
       "log-weight 2 is nan"},
      {"+inf log-weight",
       [&] {
         normalize_log_weights(std::vector<double>{0.0, kInf, 1.0, 2.0}, out);
       },
       "log-weight 1 is inf"},
      {"normalised output of the wrong size",
       [&] {
         normalize_log_weights(std::vector<double>{0.0, 1.0}, out);
       },
       "expected an output of size 2, got 4"},
      {"negative resampling threshold", [] { needs_resampling(10.0, 100, -0.5); },
       "expected a fraction in [0, 1], got -0.5"},
      {"NaN resampling threshold", [] { needs_resampling(10.0, 100, kNaN); },
       "expected a fraction in [0, 1], got nan"},
      {"threshold above one", [] { needs_resampling(10.0, 100, 1.5); },
       "expected a fraction in [0, 1], got 1.5"},
      {"NaN effective sample size", [] { needs_resampling(kNaN, 100, 0.5); }, "NaN"},
      {"weights not summing to one",
       [] {
         resample(ResamplingScheme::kSystematic, std::vector<double>{0.5, 0.4},
                  std::vector<double>{0.3}, 2);
       },
       "expected normalised weights summing to 1, got a sum of 0.9"},
      {"negative weight",
       [] {
         resample(ResamplingScheme::kMultinomial, std::vector<double>{1.1, -0.1},
                  std::vector<double>{0.3, 0.4}, 2);
       },
       "weight 1 is -0.1 (expected a finite non-negative number)"},
      {"too few uniforms",
       [] {
         resample(ResamplingScheme::kStratified, std::vector<double>{0.5, 0.5},
                  std::vector<double>{0.3, 0.4}, 5);
       },
       "expected 5 uniforms, got 2"},
      {"uniform outside (0, 1)",
       [] {
         resample(ResamplingScheme::kSystematic, std::vector<double>{0.5, 0.5},
                  std::vector<double>{1.0}, 2);
       },
       "uniform 0 is 1 (expected a value in (0, 1))"},
      {"no weights",
       [] {
         resample(ResamplingScheme::kResidual, std::vector<double>{}, std::vector<double>{}, 0);
       },
       "expected at least one weight, got none"},
      {"unknown scheme name", [] { parse_resampling_scheme("stochastic"); },
       "expected multinomial, systematic, stratified or residual, got 'stochastic'"},
      {"empty mixture", [] { MixtureProposal<2>(std::vector<Laplace<2>>{}); },
       "expected at least one component, got none"},
  };
  for (const auto& c : cases)
    EXPECT_THAT(message_of(c.call), HasSubstr(c.expected_message)) << c.what;
}

TEST(BadInput, NaNInFGivesNonFiniteStatus) {
  const auto nan_target = make_autodiff_target<2>([](const auto& x) { return x(0) * kNaN; });
  const auto r = minimize(nan_target, Vec<2>(1.0, 1.0));
  EXPECT_EQ(r.status, MinimizeStatus::kNonFinite);
  EXPECT_EQ(to_string(r.status), "non_finite");
}

TEST(BadInput, AllZeroWeightsAreReportedAndUniform) {
  // Every log-weight -inf (every sample outside the support): documented recovery, not a throw.
  const std::vector<double> lw(4, -kInf);
  std::vector<double> w(4);
  const WeightSummary s = normalize_log_weights(lw, w);
  EXPECT_TRUE(s.all_zero);
  EXPECT_EQ(s.log_mean, -kInf);
  for (double x : w) EXPECT_EQ(x, 0.25);
  EXPECT_EQ(s.ess, 4.0);
}

TEST(BadInput, SamplesOutsideSupportGetWeightZero) {
  // A target with support x > 0 but a Laplace approximation wide enough to propose x <= 0:
  // those samples get log w = -inf, are counted, and the rest are finite.
  const auto f = make_autodiff_target<1>([](const auto& x) {
    using S = typename std::decay_t<decltype(x)>::Scalar;
    using std::log;
    if (!(x(0) > 0.0)) return S(kInf);
    return x(0) - 2.0 * log(x(0));
  });
  const auto lp = Laplace<1>::make(Vec<1>(2.0), 2.0 - 2.0 * std::log(2.0), Mat<1>(0.5));
  const auto set = sample_with(f, lp, 2000, {.seed = 3});
  EXPECT_GT(set.zero_weight, 0);
  int minus_inf = 0;
  for (std::size_t j = 0; j < set.size(); ++j) {
    EXPECT_FALSE(std::isnan(set.log_weights[j]));
    if (set.log_weights[j] == -kInf) {
      ++minus_inf;
      EXPECT_LE(set.x(0, j), 0.0);
      EXPECT_EQ(set.weights[j], 0.0);
    }
  }
  EXPECT_EQ(minus_inf, set.zero_weight);
  EXPECT_TRUE(std::isfinite(set.log_Z));
}

TEST(BadInput, RandomMapFailureIsAStatus) {
  // F bounded along every ray (F = 1 - exp(-|x|^2/2)): the scalar equation F - phi = rho/2 has no
  // root once rho/2 >= 1. Those samples report kBracketFailed with weight 0; no throw, no hang.
  const auto f = make_autodiff_target<2>([](const auto& x) {
    using std::exp;
    return 1.0 - exp(-0.5 * (x(0) * x(0) + x(1) * x(1)));
  });
  const auto lp = Laplace<2>::make(Vec<2>::Zero(), 0.0, Mat<2>::Identity());
  Vec<2> x;
  double lw = 0.0;
  EXPECT_EQ(random_map_sample(f, lp, Vec<2>(1.5, 1.0), x, lw), RandomMapStatus::kBracketFailed);
  EXPECT_EQ(lw, -kInf);
  EXPECT_EQ(random_map_sample(f, lp, Vec<2>(0.3, 0.4), x, lw), RandomMapStatus::kOk);
  EXPECT_TRUE(std::isfinite(lw));
  SamplerOptions o;
  o.map = MapKind::kRandom;
  const auto set = sample_with(f, lp, 500, {.seed = 4}, o);
  EXPECT_GT(set.map_failures, 0);
  EXPECT_EQ(set.zero_weight, set.map_failures);
}

TEST(BadInput, SampleWithEveryWeightZeroHasNoEffectiveSample) {
  const auto nowhere = make_autodiff_target<1>([](const auto& x) {
    using S = typename std::decay_t<decltype(x)>::Scalar;
    return S(kInf) + 0.0 * x(0);
  });
  const auto lp = Laplace<1>::make(Vec<1>(0.0), 0.0, Mat<1>(1.0));
  const auto set = sample_with(nowhere, lp, 50, {.seed = 5});
  EXPECT_EQ(set.zero_weight, 50);
  EXPECT_EQ(set.ess, 0.0);
  EXPECT_EQ(set.log_Z, -kInf);
}

TEST(BadInput, MinusInfinityFInTheLinearMapIsACountedZeroWeight) {
  // F = -inf for x < 0 (an unbounded density there): like a random-map failure, each such sample
  // gets weight zero and is counted, instead of a +inf weight that makes normalising throw.
  const auto f = make_autodiff_target<1>([](const auto& x) {
    using S = typename std::decay_t<decltype(x)>::Scalar;
    if (x(0) < 0.0) return S(-kInf);
    return S(0.5 * (x(0) - 2.0) * (x(0) - 2.0));
  });
  const auto lp = Laplace<1>::make(Vec<1>(2.0), 0.0, Mat<1>(0.5));
  const auto set = sample_with(f, lp, 2000, {.seed = 6});
  int negative = 0;
  for (std::size_t j = 0; j < set.size(); ++j) negative += set.x(0, j) < 0.0;
  EXPECT_GT(negative, 0);
  EXPECT_EQ(set.map_failures, negative);
  EXPECT_EQ(set.zero_weight, negative);
  EXPECT_TRUE(std::isfinite(set.log_Z));
}

TEST(BadInput, SampleCountBeyondMemoryIsInvalidArgument) {
  const auto f = make_autodiff_target<1>([](const auto& x) { return 0.5 * x(0) * x(0); });
  const auto lp = Laplace<1>::make(Vec<1>(0.0), 0.0, Mat<1>(1.0));
  try {
    sample_with(f, lp, std::size_t{1} << 61, {.seed = 7});
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("expected a number of samples that fits in memory"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace implicit
