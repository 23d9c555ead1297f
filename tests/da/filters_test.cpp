// The ensemble filters against the Kalman filter on linear-Gaussian problems (an independent
// implementation below), the implicit filter's exact weights, determinism and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <span>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/filters.hpp"
#include "implicit/da/twin.hpp"
#include "refusal.hpp"
#include "weight_oracle.hpp"

namespace implicit::da {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd a_matrix() {
  MatrixXd a(3, 3);
  a << 0.9, 0.2, 0.0, -0.1, 0.8, 0.1, 0.0, 0.3, 0.7;
  return a;
}
MatrixXd h_matrix() {  // observe components 0 and 2
  MatrixXd h = MatrixXd::Zero(2, 3);
  h(0, 0) = 1.0;
  h(1, 2) = 1.0;
  return h;
}
MatrixXd r_matrix() {
  MatrixXd r(2, 2);
  r << 0.5, 0.1, 0.1, 0.4;
  return r;
}
MatrixXd q_matrix() {
  MatrixXd q(3, 3);
  q << 0.3, 0.05, 0.0, 0.05, 0.2, 0.02, 0.0, 0.02, 0.25;
  return q;
}
MatrixXd p0_matrix() {
  MatrixXd p(3, 3);
  p << 1.0, 0.3, 0.1, 0.3, 0.8, -0.2, 0.1, -0.2, 1.2;
  return p;
}
VectorXd m0_vector() { return VectorXd{{1.0, -0.5, 2.0}}; }
VectorXd y_vector() { return VectorXd{{2.1, 0.4}}; }  // far from H A m0: a real update

Problem linear_problem(bool stochastic) {
  return {std::make_shared<LinearModel>(a_matrix()), h_matrix(), r_matrix(),
          stochastic ? q_matrix() : MatrixXd()};
}

/// One Kalman cycle from N(m0, P0): forecast with A (and Q), update with y.
struct Kalman {
  VectorXd mean;
  MatrixXd cov;
};
Kalman kalman_cycle(bool stochastic) {
  const MatrixXd a = a_matrix(), h = h_matrix(), r = r_matrix();
  const VectorXd mf = a * m0_vector();
  MatrixXd pf = a * p0_matrix() * a.transpose();
  if (stochastic) pf += q_matrix();
  const MatrixXd s = h * pf * h.transpose() + r;
  const MatrixXd k = pf * h.transpose() * s.inverse();
  return {mf + k * (y_vector() - h * mf), (MatrixXd::Identity(3, 3) - k * h) * pf};
}

/// N members whose sample mean and (N-1)-covariance are exactly m and P: normals, centred,
/// whitened by their own sample covariance, coloured by P's factor.
MatrixXd members_with_exact_moments(int n_members, const VectorXd& m, const MatrixXd& p) {
  MatrixXd z(3, n_members);
  for (int j = 0; j < n_members; ++j) {
    Rng rng({77, 0, static_cast<std::uint64_t>(j), purpose::kInitial});
    auto col = z.col(j);
    rng.fill_normal(col);
  }
  z = z.colwise() - z.rowwise().mean();
  const MatrixXd c = z * z.transpose() / (n_members - 1);
  const MatrixXd lc = c.llt().matrixL();
  const MatrixXd lp = p.llt().matrixL();
  z = lp * lc.triangularView<Eigen::Lower>().solve(z);
  return z.colwise() + m;
}

MatrixXd sample_cov(const MatrixXd& e) {
  const MatrixXd a = e.colwise() - e.rowwise().mean();
  return a * a.transpose() / static_cast<double>(e.cols() - 1);
}

// A deterministic linear model maps an ensemble with the prior's exact moments to one with the
// forecast's exact moments, so the ETKF (a square-root filter: no sampling in the analysis) must
// give Kalman's mean and covariance to round-off.
TEST(Etkf, MatchesKalmanExactlyForAnEnsembleWithExactMoments) {
  const Kalman kf = kalman_cycle(false);
  for (int n : {4, 10, 100}) {
    EnsembleFilter f(linear_problem(false), {.method = Method::kEtkf, .members = n});
    f.initialize(members_with_exact_moments(n, m0_vector(), p0_matrix()));
    const Analysis& a = f.assimilate(y_vector());
    EXPECT_LT((a.mean - kf.mean).cwiseAbs().maxCoeff(), 1e-12) << "N = " << n;
    EXPECT_LT((sample_cov(f.members()) - kf.cov).cwiseAbs().maxCoeff(), 1e-12) << "N = " << n;
  }
}

// Perturbed observations with exact forecast moments: the gain is Kalman's exactly, so the mean
// is Kalman's plus K L_R ebar with ebar ~ N(0, I/N): standard error sqrt((K R K^T)_ii / N).
// The covariance is (I-KH) Pf (I-KH)^T + K R_hat K^T + cross terms, whose entries have sampling
// standard error at most sqrt((Pa_ii Pa_jj + Pa_ij^2) / N) (a Gaussian sample covariance's).
// Checked within 5 standard errors at N = 100 and 10000: the error shrinks like 1/sqrt(N).
TEST(Enkf, MeanAndCovarianceApproachKalmanWithinTheSamplingError) {
  const Kalman kf = kalman_cycle(false);
  const MatrixXd a = a_matrix(), h = h_matrix(), r = r_matrix();
  const MatrixXd pf = a * p0_matrix() * a.transpose();
  const MatrixXd k = pf * h.transpose() * (h * pf * h.transpose() + r).inverse();
  const MatrixXd krk = k * r * k.transpose();
  for (int n : {100, 10000}) {
    EnsembleFilter f(linear_problem(false), {.method = Method::kEnkf, .members = n, .seed = 5});
    f.initialize(members_with_exact_moments(n, m0_vector(), p0_matrix()));
    const Analysis& an = f.assimilate(y_vector());
    const MatrixXd cov = sample_cov(f.members());
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(an.mean(i), kf.mean(i), 5.0 * std::sqrt(krk(i, i) / n)) << "N=" << n;
      for (int j = 0; j < 3; ++j) {
        const double se =
            std::sqrt((kf.cov(i, i) * kf.cov(j, j) + kf.cov(i, j) * kf.cov(i, j)) / n);
        EXPECT_NEAR(cov(i, j), kf.cov(i, j), 5.0 * se) << "N=" << n << " (" << i << "," << j << ")";
      }
    }
  }
}

// Particle filters from N(m0, P0) through the stochastic model: the self-normalised importance
// estimate of the posterior mean has standard error ~ sqrt(Pa_ii / ESS) (Kong's effective sample
// size); checked within 5 of them with 20000 particles.
void expect_particle_mean_near_kalman(Method method, ImplicitMap map) {
  const Kalman kf = kalman_cycle(true);
  EnsembleFilter f(linear_problem(true),
                   {.method = method, .members = 20000, .resample_threshold = 0.0, .map = map});
  f.initialize(m0_vector(), p0_matrix());
  const Analysis& a = f.assimilate(y_vector());
  EXPECT_EQ(a.sampling_failures, 0);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(a.mean(i), kf.mean(i), 5.0 * std::sqrt(kf.cov(i, i) / a.ess))
        << to_string(method) << " component " << i << ", ESS " << a.ess;
}

TEST(ParticleFilters, BootstrapMeanMatchesKalmanWithinTheStandardError) {
  expect_particle_mean_near_kalman(Method::kBootstrap, ImplicitMap::kLinear);
}
TEST(ParticleFilters, ImplicitMeanMatchesKalmanWithinTheStandardError) {
  expect_particle_mean_near_kalman(Method::kImplicit, ImplicitMap::kLinear);
  expect_particle_mean_near_kalman(Method::kImplicit, ImplicitMap::kRandom);
}

// Linear-Gaussian: F is quadratic, so the implicit sample is drawn from p(x | x', y) exactly (the
// optimal proposal) and its weight is p(y | x') = N(y; H A x', H Q H^T + R) whatever the
// reference variable: the normalised weights are that density normalised, to round-off, and
// members with one parent have equal weights.
TEST(ParticleFilters, ImplicitWeightsAreTheOptimalProposalsExactly) {
  const MatrixXd a = a_matrix(), h = h_matrix();
  const MatrixXd s = h * q_matrix() * h.transpose() + r_matrix();
  const Eigen::LLT<MatrixXd> s_llt(s);
  for (ImplicitMap map : {ImplicitMap::kLinear, ImplicitMap::kRandom}) {
    EnsembleFilter f(
        linear_problem(true),
        {.method = Method::kImplicit, .members = 50, .resample_threshold = 0.0, .map = map});
    f.initialize(m0_vector(), p0_matrix());
    const MatrixXd parents = f.members();
    f.assimilate(y_vector());
    std::vector<double> log_p(50);
    for (int j = 0; j < 50; ++j) {
      const VectorXd d = y_vector() - h * a * parents.col(j);
      log_p[static_cast<std::size_t>(j)] = -0.5 * d.dot(s_llt.solve(d));
    }
    test::expect_weights_proportional_to(f.weights(), log_p, "linear-Gaussian");

    EnsembleFilter g(
        linear_problem(true),
        {.method = Method::kImplicit, .members = 20, .resample_threshold = 0.0, .map = map});
    g.initialize(MatrixXd(m0_vector().replicate(1, 20)));
    g.assimilate(y_vector());
    for (double w : g.weights()) EXPECT_NEAR(w * 20.0, 1.0, 1e-10);
  }
}

// The same exactness in other dimensions: n = 10 takes the fixed-size path of the implicit
// filter (the Lorenz-96 benchmark's size), n = 5 the dynamic one.
TEST(ParticleFilters, ImplicitWeightsAreExactInEveryDimension) {
  for (int n : {5, 10}) {
    MatrixXd a = 0.9 * MatrixXd::Identity(n, n);
    for (int i = 0; i + 1 < n; ++i) a(i, i + 1) = 0.1;
    const int p = (n + 1) / 2;
    MatrixXd h = MatrixXd::Zero(p, n);
    for (int i = 0; i < p; ++i) h(i, 2 * i) = 1.0;
    const MatrixXd q = 0.3 * MatrixXd::Identity(n, n), r = 0.5 * MatrixXd::Identity(p, p);
    const Problem problem{std::make_shared<LinearModel>(a), h, r, q};
    EnsembleFilter f(problem,
                     {.method = Method::kImplicit, .members = 30, .resample_threshold = 0.0});
    f.initialize(VectorXd::Constant(n, 1.0), MatrixXd::Identity(n, n));
    const MatrixXd parents = f.members();
    const VectorXd y = VectorXd::LinSpaced(p, -1.0, 2.0);
    f.assimilate(y);
    const Eigen::LLT<MatrixXd> s_llt(h * q * h.transpose() + r);
    std::vector<double> log_p(30);
    for (int j = 0; j < 30; ++j) {
      const VectorXd d = y - h * a * parents.col(j);
      log_p[static_cast<std::size_t>(j)] = -0.5 * d.dot(s_llt.solve(d));
    }
    test::expect_weights_proportional_to(f.weights(), log_p, "n = " + std::to_string(n));
  }
}

TEST(TwinExperiment, RmseIsTheMeanOfTheScoredCyclesRootMeanSquareErrors) {
  TwinSettings s{.cycles = 6,
                 .interval = 1.0,
                 .burn_in = 2.5,
                 .truth0 = m0_vector(),
                 .mean0 = m0_vector(),
                 .cov0 = p0_matrix(),
                 .seed = 3,
                 .keep_history = true};
  const auto r = run_twin(linear_problem(true), {.method = Method::kEtkf, .members = 5}, s);
  ASSERT_EQ(r.means.size(), 6u);
  EXPECT_EQ(r.scored_cycles, 4);  // times 3, 4, 5, 6 > 2.5
  double by_hand = 0.0;
  for (std::size_t k = 2; k < 6; ++k) {
    const VectorXd e = r.means[k] - r.truth[k];
    by_hand += std::sqrt((e(0) * e(0) + e(1) * e(1) + e(2) * e(2)) / 3.0);
  }
  by_hand /= 4.0;
  EXPECT_DOUBLE_EQ(r.rmse_a, by_hand);
  EXPECT_DOUBLE_EQ(analysis_rmse(r.means, r.truth, 2), by_hand);
}

TEST(TwinExperiment, SameSeedSameNumbersForAnyThreadCount) {
  for (Method m : {Method::kBootstrap, Method::kImplicit, Method::kEnkf, Method::kEtkf}) {
    TwinSettings s{.cycles = 5,
                   .interval = 1.0,
                   .truth0 = m0_vector(),
                   .mean0 = m0_vector(),
                   .cov0 = p0_matrix(),
                   .seed = 11,
                   .keep_history = true};
    const FilterOptions o{.method = m, .members = 200, .jitter = 0.1, .inflation = 1.05};
    TwinResult one, two;
    {
      ThreadLimit limit(1);
      one = run_twin(linear_problem(true), o, s);
    }
    {
      ThreadLimit limit(2);
      two = run_twin(linear_problem(true), o, s);
    }
    for (std::size_t k = 0; k < one.means.size(); ++k)
      EXPECT_EQ((one.means[k] - two.means[k]).cwiseAbs().maxCoeff(), 0.0) << to_string(m);
    EXPECT_EQ(one.rmse_a, two.rmse_a);
  }
}

using implicit::test_support::expect_refused;

TEST(EnsembleFilter, RefusesBadInput) {
  const Problem p = linear_problem(true);
  expect_refused([&] { EnsembleFilter(p, {.members = 1}); }, "at least 2 members (N), got 1");
  Problem bad_r = p;
  bad_r.R(1, 1) = -1.0;
  expect_refused([&] { EnsembleFilter(bad_r, {}); }, "observation noise R: expected a positive");
  Problem bad_q = p;
  bad_q.Q(0, 1) = 5.0;
  expect_refused([&] { EnsembleFilter(bad_q, {}); }, "model noise Q: expected a symmetric");
  bad_q.Q(1, 0) = 5.0;
  expect_refused([&] { EnsembleFilter(bad_q, {}); }, "model noise Q: expected a positive");
  Problem bad_h = p;
  bad_h.H = MatrixXd::Zero(2, 4);
  expect_refused([&] { EnsembleFilter(bad_h, {}); }, "expected 3 columns");
  expect_refused([&] { EnsembleFilter(linear_problem(false), {.method = Method::kImplicit}); },
                 "expected a jitter > 0");
  expect_refused([&] { EnsembleFilter(p, {.inflation = 0.9}); }, "inflation >= 1");
  expect_refused([&] { EnsembleFilter(p, {.resample_threshold = 1.5}); }, "in [0, 1]");
  EnsembleFilter f(p, {});
  f.initialize(m0_vector(), p0_matrix());
  expect_refused(
      [&] {
        f.assimilate(VectorXd{{1.0, std::nan("")}});
      },
      "observation 1: expected finite values");
  expect_refused(
      [&] {
        f.assimilate(VectorXd{{1.0, 2.0, 3.0}});
      },
      "observation 1: expected 2 values");
  expect_refused([] { parse_method("kalman"); }, "got 'kalman'");
}

}  // namespace
}  // namespace implicit::da
