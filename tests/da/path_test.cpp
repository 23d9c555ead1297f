// Observations after K > 1 noisy model intervals: the implicit path objective's derivatives
// against finite differences, its exact weights on a linear model (closed form) and on Lorenz-63
// (against a brute-force integral over prior paths), the filters against each other, the twin
// truth, and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/filters.hpp"
#include "implicit/da/path_objective.hpp"
#include "implicit/da/smoother.hpp"
#include "implicit/da/twin.hpp"
#include "refusal.hpp"
#include "weight_oracle.hpp"

namespace implicit::da {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Lorenz-63 over intervals of 0.05 (5 RK4 steps), K = 4 intervals per observation of x and z,
/// Q = 0.5 I per interval, R = I: the end of a path is visibly nonlinear in its noises.
Problem lorenz63_path_problem() {
  Problem p{std::make_shared<Lorenz63Model>(Lorenz63{}, 0.01, 5), MatrixXd::Zero(2, 3),
            MatrixXd::Identity(2, 2), 0.5 * MatrixXd::Identity(3, 3)};
  p.H(0, 0) = 1.0;
  p.H(1, 2) = 1.0;
  p.steps_per_observation = 4;
  return p;
}

const VectorXd kParent{{1.509, -1.531, 25.46}};

/// An observation 1.5 standard deviations (per component) off the noise-free path's end: a real
/// update, yet likely enough under the prior paths for a brute-force integral.
VectorXd off_path_observation(const Problem& p) {
  VectorXd x = kParent;
  ForecastWorkspace work;
  for (int k = 0; k < p.steps_per_observation; ++k) p.model->forecast(x, work);
  return p.H * x + VectorXd{{1.5, -1.5}};
}

TEST(PathObjective, GradientAndGaussNewtonHessianMatchFiniteDifferences) {
  const Problem p = lorenz63_path_problem();
  const VectorXd y{{3.0, 20.0}};
  const PathTerms t(p, p.Q, y);
  PathObjective::Scratch s;
  prepare_scratch(p, s);
  const PathObjective f(p, t, kParent, s);
  const int size = 12;
  VectorXd w(size);
  Rng rng({5, 0, 0, purpose::kData});
  rng.fill_normal(w);
  w *= 0.7;
  VectorXd grad(size);
  MatrixXd hess(size, size);
  f.evaluate(w, &grad, &hess);
  // Central differences of F (gradient) and of x_K (G = dx_K/dw, for the Gauss-Newton Hessian
  // blockdiag(Q^-1) + G^T H^T R^-1 H G with R = I).
  const double h = 1e-6;
  MatrixXd g(3, size);
  for (int i = 0; i < size; ++i) {
    VectorXd up = w, down = w;
    up(i) += h;
    down(i) -= h;
    const double fd =
        (f.evaluate(up, nullptr, nullptr) - f.evaluate(down, nullptr, nullptr)) / (2.0 * h);
    EXPECT_NEAR(grad(i), fd, 1e-5 * std::max(1.0, std::abs(fd))) << "component " << i;
    VectorXd x_up(3), x_down(3);
    f.end_state(up, x_up);
    f.end_state(down, x_down);
    g.col(i) = (x_up - x_down) / (2.0 * h);
  }
  MatrixXd expected = g.transpose() * p.H.transpose() * p.H * g;
  for (int i = 0; i < 4; ++i) expected.block(3 * i, 3 * i, 3, 3) += 2.0 * MatrixXd::Identity(3, 3);
  EXPECT_LT((hess - expected).cwiseAbs().maxCoeff(), 1e-5 * expected.cwiseAbs().maxCoeff());
}

// Linear model, K = 3: x_K = A^3 x' + A^2 w_1 + A w_2 + w_3, so the implicit sample is exact and
// every weight is p(y | x') = N(y; H A^3 x', H (Q + A Q A^T + A^2 Q A^2^T) H^T + R), the same for
// every reference variable.
TEST(PathFilter, ImplicitWeightsAreThePathLikelihoodExactlyOnALinearModel) {
  MatrixXd a(3, 3);
  a << 0.9, 0.2, 0.0, -0.1, 0.8, 0.1, 0.0, 0.3, 0.7;
  Problem p{std::make_shared<LinearModel>(a), MatrixXd::Zero(2, 3), 0.4 * MatrixXd::Identity(2, 2),
            0.3 * MatrixXd::Identity(3, 3)};
  p.H(0, 0) = 1.0;
  p.H(1, 2) = 1.0;
  p.steps_per_observation = 3;
  const VectorXd y{{2.1, 0.4}};
  MatrixXd sum = p.Q, power = MatrixXd::Identity(3, 3);
  for (int i = 1; i < 3; ++i) {
    power = a * power;
    sum += power * p.Q * power.transpose();
  }
  const Eigen::LLT<MatrixXd> s_llt(p.H * sum * p.H.transpose() + p.R);
  const MatrixXd a3 = a * a * a;
  for (ImplicitMap map : {ImplicitMap::kLinear, ImplicitMap::kRandom}) {
    EnsembleFilter f(
        p, {.method = Method::kImplicit, .members = 40, .resample_threshold = 0.0, .map = map});
    f.initialize(VectorXd{{1.0, -0.5, 2.0}}, MatrixXd::Identity(3, 3));
    const MatrixXd parents = f.members();
    const Analysis& analysis = f.assimilate(y);
    EXPECT_EQ(analysis.sampling_failures, 0);
    std::vector<double> log_p(40);
    for (int j = 0; j < 40; ++j) {
      const VectorXd d = y - p.H * a3 * parents.col(j);
      log_p[static_cast<std::size_t>(j)] = -0.5 * d.dot(s_llt.solve(d));
    }
    test::expect_weights_proportional_to(f.weights(), log_p, "K = 3");
  }
}

/// log N(y; H x, R) with R = I (lorenz63_path_problem's).
double log_likelihood(const Problem& p, const VectorXd& y, const VectorXd& x) {
  return -0.5 * (y - p.H * x).squaredNorm() - std::log(2.0 * kPi);
}

// Nonlinear paths: the implicit weight is an unbiased estimate of p(y | x') for any reference
// variable, so its mean over samples must match the brute-force mean of p(y | x_K) over prior
// paths (x_K from the model with N(0, Q) noises, computed here without the objective).
TEST(PathObjective, MeanImplicitWeightIsThePathLikelihoodOnLorenz63) {
  const Problem p = lorenz63_path_problem();
  const VectorXd y = off_path_observation(p);
  const PathTerms t(p, p.Q, y);
  PathObjective::Scratch s;
  prepare_scratch(p, s);
  const PathObjective f(p, t, kParent, s);
  const auto r = newton_minimize<DenseFactor<Eigen::Dynamic>>(f, VectorXd::Zero(12));
  ASSERT_TRUE(r.factor_ok);
  const int m = 20000;
  double implicit_sum = 0.0, implicit_sq = 0.0;
  VectorXd xi(12), w(12);
  for (int i = 0; i < m; ++i) {
    Rng rng({7, 1, static_cast<std::uint64_t>(i), purpose::kReference});
    rng.fill_normal(xi);
    const double weight = std::exp(linear_map(f, r.x, r.factor, xi, w));
    implicit_sum += weight;
    implicit_sq += weight * weight;
  }
  const int b = 400000;
  double brute_sum = 0.0, brute_sq = 0.0;
  const MatrixXd lq = p.Q.llt().matrixL();
  ForecastWorkspace work;
  VectorXd x(3), z(3);
  for (int i = 0; i < b; ++i) {
    Rng rng({7, 2, static_cast<std::uint64_t>(i), purpose::kData});
    x = kParent;
    for (int k = 0; k < 4; ++k) {
      p.model->forecast(x, work);
      rng.fill_normal(z);
      x += lq * z;
    }
    const double like = std::exp(log_likelihood(p, y, x));
    brute_sum += like;
    brute_sq += like * like;
  }
  const double mi = implicit_sum / m, mb = brute_sum / b;
  const double se_i = std::sqrt((implicit_sq / m - mi * mi) / m);
  const double se_b = std::sqrt((brute_sq / b - mb * mb) / b);
  // The implicit weights vary (the path posterior is not Gaussian) but far less than the prior
  // paths' likelihoods: that is the point of the proposal.
  EXPECT_LT(std::sqrt(implicit_sq / m - mi * mi) / mi, std::sqrt(brute_sq / b - mb * mb) / mb);
  EXPECT_NEAR(mi, mb, 4.0 * std::hypot(se_i, se_b))
      << "implicit " << mi << " +- " << se_i << ", prior paths " << mb << " +- " << se_b;
}

/// Weighted mean of the members and its delta-method standard error per component.
struct WeightedMean {
  VectorXd mean, se;
};
WeightedMean weighted_mean(const EnsembleFilter& f) {
  const MatrixXd x = f.members();
  const auto w = f.weights();
  WeightedMean r{VectorXd::Zero(x.rows()), VectorXd::Zero(x.rows())};
  for (Eigen::Index j = 0; j < x.cols(); ++j) r.mean += w[static_cast<std::size_t>(j)] * x.col(j);
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    const double wj = w[static_cast<std::size_t>(j)];
    r.se += (wj * wj) * (x.col(j) - r.mean).cwiseAbs2();
  }
  r.se = r.se.cwiseSqrt();
  return r;
}

// Both particle filters estimate E[x_K | x', y] from one parent: the bootstrap one by K noisy
// forecasts weighted by the likelihood, the implicit one by the path objective. They must agree
// within their standard errors.
TEST(PathFilter, BootstrapAndImplicitAgreeOnTheMeanOfTheNonlinearPathPosterior) {
  const Problem p = lorenz63_path_problem();
  const VectorXd y = off_path_observation(p);
  const auto one_cycle = [&](Method method, int members) {
    EnsembleFilter f(p, {.method = method, .members = members, .resample_threshold = 0.0});
    f.initialize(MatrixXd(kParent.replicate(1, members)));
    f.assimilate(y);
    return weighted_mean(f);
  };
  const WeightedMean boot = one_cycle(Method::kBootstrap, 200000);
  const WeightedMean imp = one_cycle(Method::kImplicit, 2000);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(imp.mean(i), boot.mean(i), 4.0 * std::hypot(imp.se(i), boot.se(i)))
        << "component " << i << ": implicit " << imp.mean(i) << " +- " << imp.se(i)
        << ", bootstrap " << boot.mean(i) << " +- " << boot.se(i);
}

TEST(PathTwin, TheTruthTakesKIntervalsPerObservation) {
  MatrixXd a(2, 2);
  a << 0.9, 0.3, -0.2, 0.8;
  Problem p{std::make_shared<LinearModel>(a), MatrixXd::Identity(2, 2),
            0.1 * MatrixXd::Identity(2, 2), MatrixXd()};
  p.steps_per_observation = 3;
  const VectorXd x0{{1.0, 2.0}};
  TwinSettings s{.cycles = 4,
                 .interval = 1.0,
                 .truth0 = x0,
                 .mean0 = x0,
                 .cov0 = MatrixXd::Identity(2, 2),
                 .keep_history = true};
  const auto r = run_twin(p, {.method = Method::kEtkf, .members = 5}, s);
  MatrixXd power = MatrixXd::Identity(2, 2);
  for (int k = 0; k < 4; ++k) {
    power = a * a * a * power;
    EXPECT_LT((r.truth[static_cast<std::size_t>(k)] - power * x0).cwiseAbs().maxCoeff(), 1e-12);
  }
}

using implicit::test_support::expect_refused;

TEST(PathFilter, RefusesWhatItCannotSample) {
  Problem p = lorenz63_path_problem();
  p.steps_per_observation = 0;
  expect_refused([&] { EnsembleFilter(p, {}); }, "at least 1 model interval per observation");
  Problem deterministic = lorenz63_path_problem();
  deterministic.Q.resize(0, 0);
  expect_refused(
      [&] {
        EnsembleFilter(deterministic, {.method = Method::kImplicit,
                                       .jitter = 0.5,
                                       .regularisation = Regularisation::kCovariance});
      },
      "with 4 model intervals per observation");
  deterministic.steps_per_observation = 2;
  expect_refused([&] { ImplicitSmoother(deterministic, {}); },
                 "expected one model interval per observation");
  expect_refused(
      [&] {
        PathTerms(lorenz63_path_problem(), MatrixXd::Identity(3, 3), VectorXd{{1.0, std::nan("")}});
      },
      "implicit path: expected a finite observation of size 2");
}

/// x <- x^2 in every component: a truth beyond 1 in size grows doubly exponentially, and an
/// ensemble that follows it overflows first (its members spread around the truth).
class SquaringModel final : public Model {
 public:
  int dim() const override { return 2; }
  void forecast(Eigen::VectorXd& x, ForecastWorkspace&) const override { x = x.cwiseAbs2(); }
  std::string name() const override { return "squaring"; }
};

TEST(TwinExperiment, AFilterThatDivergesStopsWithNoScore) {
  const Problem p{std::make_shared<SquaringModel>(), MatrixXd::Identity(2, 2),
                  MatrixXd::Identity(2, 2), MatrixXd()};
  // The truth 2^(2^k) overflows at cycle 10; the members overflow before.
  const VectorXd x0{{2.0, 0.5}};
  const TwinSettings s{.cycles = 9,
                       .interval = 1.0,
                       .truth0 = x0,
                       .mean0 = x0,
                       .cov0 = MatrixXd::Identity(2, 2),
                       .keep_history = true};
  const auto r = run_twin(p, {.method = Method::kEtkf, .members = 5}, s);
  EXPECT_GT(r.diverged_at, 0);
  ASSERT_LT(r.diverged_at, 10);
  EXPECT_EQ(r.means.size(), static_cast<std::size_t>(r.diverged_at - 1));  // the run stopped
  EXPECT_TRUE(std::isnan(r.rmse_a));
  EXPECT_TRUE(std::isnan(r.spread_a));
  // A truth that overflows at once is the model's fault, not the filter's: refused.
  const TwinSettings unstable{.cycles = 9,
                              .interval = 1.0,
                              .truth0 = VectorXd{{1e200, 0.5}},
                              .mean0 = x0,
                              .cov0 = MatrixXd::Identity(2, 2)};
  expect_refused([&] { run_twin(p, {.method = Method::kEtkf, .members = 5}, unstable); },
                 "the truth is not finite at cycle 1");
}

}  // namespace
}  // namespace implicit::da
