// The implicit smoother (spec §3.14, "Implicit smoother"): on a linear model the window posterior
// is Gaussian, so the weights are equal and the samples match the closed-form posterior; F's
// gradient against finite differences; determinism over thread counts; bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/smoother.hpp"
#include "implicit/da/twin.hpp"

namespace implicit::da {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd lin_a() {
  MatrixXd a(3, 3);
  a << 0.95, 0.3, 0.0, -0.2, 0.9, 0.1, 0.0, 0.25, 0.8;
  return a;
}
Problem lin_problem() {  // perfect linear model, components 0 and 2 observed
  MatrixXd h = MatrixXd::Zero(2, 3);
  h(0, 0) = 1.0;
  h(1, 2) = 1.0;
  return {std::make_shared<LinearModel>(lin_a()), h, 0.5 * MatrixXd::Identity(2, 2), MatrixXd()};
}

// One cycle at a full window (cycle > L, so the members first move one interval) is exact Bayes
// for the Gaussian background fitted to the shifted members: x0 ~ N(mu, P) with
// P = (B^-1 + G^T R^-1 G)^-1, mu = P (B^-1 b + G^T R^-1 y), G = H A^L.
TEST(ImplicitSmoother, LinearGaussianWindowMatchesClosedForm) {
  const Problem p = lin_problem();
  SmootherOptions o{.members = 4000, .lag = 3, .inflation = 1.0, .starts = 2, .seed = 11};
  ImplicitSmoother s(p, o);
  s.initialize(VectorXd::Zero(3), MatrixXd::Identity(3, 3));
  const VectorXd y1(Eigen::Vector2d(0.3, -0.4));
  for (int k = 0; k < 3; ++k) s.assimilate(y1 * (1.0 + k));  // the window fills (no shift)
  const MatrixXd before = s.members();
  const auto w0 = s.weights();
  const MatrixXd a = lin_a();
  // The background the smoother must fit: weighted moments of A x_j, unbiased (1 - sum w^2).
  VectorXd b = VectorXd::Zero(3);
  double sum_sq = 0.0;
  for (Eigen::Index j = 0; j < before.cols(); ++j) {
    b += w0[static_cast<std::size_t>(j)] * a * before.col(j);
    sum_sq += w0[static_cast<std::size_t>(j)] * w0[static_cast<std::size_t>(j)];
  }
  MatrixXd bcov = MatrixXd::Zero(3, 3);
  for (Eigen::Index j = 0; j < before.cols(); ++j) {
    const VectorXd d = a * before.col(j) - b;
    bcov += w0[static_cast<std::size_t>(j)] * d * d.transpose();
  }
  bcov /= 1.0 - sum_sq;
  const VectorXd y(Eigen::Vector2d(1.1, -0.7));
  s.assimilate(y);
  ASSERT_EQ(s.window_start(), 1);
  EXPECT_LT((s.background_mean() - b).norm(), 1e-10);
  EXPECT_LT((s.background_cov() - bcov).norm(), 1e-10);
  const MatrixXd g = p.H * a * a * a;
  const MatrixXd r_inv = p.R.inverse();
  const MatrixXd prec = bcov.inverse() + g.transpose() * r_inv * g;
  const MatrixXd post = prec.inverse();
  const VectorXd mu = post * (bcov.inverse() * b + g.transpose() * r_inv * y);
  EXPECT_LT((s.mode() - mu).norm(), 1e-8);
  // Gauss-Newton is exact here: every weight is 1/N up to rounding.
  for (double w : s.weights()) EXPECT_NEAR(w * o.members, 1.0, 1e-9);
  // Sample mean: N (m - mu)^T P^-1 (m - mu) ~ chi^2_3 (the samples are exact draws of N(mu, P));
  // its 0.999 quantile is 16.27.
  const MatrixXd x = s.members();
  const VectorXd m = x.rowwise().mean();
  const VectorXd e = m - mu;
  EXPECT_LT(o.members * e.dot(prec * e), 16.27);
  // Sample variances: sd of s^2 is sqrt(2 / (N - 1)) sigma^2; 4 of those bound each.
  const MatrixXd d = x.colwise() - m;
  const MatrixXd c = d * d.transpose() / (o.members - 1.0);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(c(i, i), post(i, i), 4.0 * std::sqrt(2.0 / (o.members - 1.0)) * post(i, i));
  // The analysis is the mean of the window end A^3 x0_j.
  const auto& an = s.assimilate(y);  // next cycle, same checks not repeated; mean consistent
  EXPECT_LT((an.mean - s.window_end_members().rowwise().mean()).norm(), 1e-9);
}

// Kernel background (bandwidth h < 1) on the linear model: the prior is the mixture
// (1/N) sum_j N(c_j, h^2 B), c_j = a x_j + (1 - a) b, so the posterior is a Gaussian mixture whose
// component j has the evidence N(y; G c_j, G h^2 B G^T + R) and the mean
// mu_j = P (B_h^-1 c_j + G^T R^-1 y), P = (B_h^-1 + G^T R^-1 G)^-1 (G = H A). F of each kernel is
// quadratic, so member j's weight is exactly its component's evidence (normalised) and its draw
// an exact draw of N(mu_j, P).
TEST(ImplicitSmoother, KernelWeightsAreTheComponentEvidencesOnALinearModel) {
  const Problem p = lin_problem();
  const int count = 3000;
  const double h = 0.5, a = std::sqrt(1.0 - h * h);
  SmootherOptions o{.members = count, .lag = 1, .inflation = 1.1, .bandwidth = h, .seed = 21};
  ImplicitSmoother s(p, o);
  MatrixXd x(3, count);
  {  // members from a skewed cloud, so that the kernels' evidences differ
    Rng rng({7, 0, 0, purpose::kInitial});
    for (int j = 0; j < count; ++j) {
      const double u = rng.normal(), v = rng.normal(), w = rng.normal();
      x.col(j) = Eigen::Vector3d(u * u, v + 0.5 * u, 0.3 * w);
    }
  }
  s.initialize(x);
  const VectorXd y(Eigen::Vector2d(1.4, -0.2));
  s.assimilate(y);  // cycle 1: window start 0, one interval; equal weights, so no member is lost
  const VectorXd b = x.rowwise().mean();
  const MatrixXd d = x.colwise() - b;
  const MatrixXd bcov = d * d.transpose() / (count - 1.0) * o.inflation * o.inflation;
  EXPECT_LT((s.background_mean() - b).norm(), 1e-10);
  EXPECT_LT((s.background_cov() - bcov).norm(), 1e-10);
  const MatrixXd g = p.H * lin_a();
  const MatrixXd bh_inv = (h * h * bcov).inverse();
  const MatrixXd r_inv = p.R.inverse();
  const MatrixXd post = (bh_inv + g.transpose() * r_inv * g).inverse();
  const Eigen::LLT<MatrixXd> s_llt(g * (h * h * bcov) * g.transpose() + p.R);
  std::vector<double> log_evidence(count);
  VectorXd mean = VectorXd::Zero(3);
  double top = -1e300;
  for (int j = 0; j < count; ++j) {
    const VectorXd c = a * x.col(j) + (1.0 - a) * b;
    const VectorXd r = y - g * c;
    log_evidence[j] = -0.5 * r.dot(s_llt.solve(r));  // the shared constants cancel
    top = std::max(top, log_evidence[j]);
  }
  std::vector<double> pi(count);
  double total = 0.0;
  for (int j = 0; j < count; ++j) total += pi[j] = std::exp(log_evidence[j] - top);
  double sum_sq = 0.0;
  for (int j = 0; j < count; ++j) {
    pi[j] /= total;
    sum_sq += pi[j] * pi[j];
    mean += pi[j] * post * (bh_inv * (a * x.col(j) + (1.0 - a) * b) + g.transpose() * r_inv * y);
  }
  // Systematic resampling of equal weights keeps every member once, in order.
  const auto w = s.weights();
  for (int j = 0; j < count; ++j) EXPECT_NEAR(w[j], pi[j], 1e-9 * pi[j]) << j;
  // The weighted mean of the members: one exact draw per component, so its error has the
  // covariance (sum_j pi_j^2) P, and e^T ((sum pi^2) P)^-1 e ~ chi^2_3 (0.999 quantile 16.27).
  const VectorXd e = s.members() * Eigen::Map<const VectorXd>(w.data(), count) - mean;
  EXPECT_LT(e.dot(post.inverse() * e) / sum_sq, 16.27);
}

TEST(ImplicitSmoother, GradientMatchesFiniteDifferencesOnLorenz63) {
  Problem p{std::make_shared<Lorenz63Model>(Lorenz63{}, 0.01, 25), MatrixXd::Identity(3, 3),
            2.0 * MatrixXd::Identity(3, 3), MatrixXd()};
  WindowTerms t;
  t.b = Eigen::Vector3d(1.5, -1.5, 25.0);
  MatrixXd bc(3, 3);
  bc << 2.0, 0.5, 0.1, 0.5, 1.5, -0.3, 0.1, -0.3, 1.0;
  t.b_lower = bc.llt().matrixL();
  t.b_inv = bc.inverse();
  t.r_lower = p.R.llt().matrixL();
  t.y = Eigen::Vector3d(-3.0, -5.0, 20.0);
  t.lag = 2;
  t.set_log_norm();
  WindowObjective::Scratch scratch;
  prepare_scratch(p, scratch);
  const WindowObjective f(p, t, scratch);
  const VectorXd x = Eigen::Vector3d(1.2, -1.1, 24.3);
  VectorXd g(3);
  MatrixXd h(3, 3);
  f.evaluate(x, &g, &h);
  // Central differences: error O(eps^2 F''') plus rounding O(ulp F / eps); eps = 1e-5 keeps both
  // below 1e-4 relative for F of order 1e2 and derivatives up to ~1e3 here.
  const double eps = 1e-5;
  for (int i = 0; i < 3; ++i) {
    VectorXd xp = x, xm = x;
    xp(i) += eps;
    xm(i) -= eps;
    const double fd =
        (f.evaluate(xp, nullptr, nullptr) - f.evaluate(xm, nullptr, nullptr)) / (2.0 * eps);
    EXPECT_NEAR(g(i), fd, 1e-4 * (1.0 + std::abs(fd))) << i;
  }
  EXPECT_LT((h - h.transpose()).norm(), 1e-9 * h.norm());
  Eigen::LLT<MatrixXd> llt(h);
  EXPECT_EQ(llt.info(), Eigen::Success);  // Gauss-Newton: SPD
}

TEST(ImplicitSmoother, SameBitsForAnyThreadCount) {
  Problem p{std::make_shared<Lorenz63Model>(Lorenz63{}, 0.01, 25), MatrixXd::Identity(3, 3),
            2.0 * MatrixXd::Identity(3, 3), MatrixXd()};
  TwinSettings ts{.cycles = 40,
                  .interval = 0.25,
                  .burn_in = 1.0,
                  .truth0 = Eigen::Vector3d(1.509, -1.531, 25.46),
                  .mean0 = Eigen::Vector3d(1.509, -1.531, 25.46),
                  .cov0 = 2.0 * MatrixXd::Identity(3, 3),
                  .seed = 5,
                  .keep_history = true};
  for (const double h : {1.0, 0.6}) {  // the Gaussian background and the kernels
    const SmootherOptions o{
        .members = 40, .lag = 3, .inflation = 1.0, .starts = 3, .bandwidth = h, .seed = 5};
    TwinResult one, two;
    {
      ThreadLimit limit(1);
      one = run_twin(p, o, ts);
    }
    {
      ThreadLimit limit(2);
      two = run_twin(p, o, ts);
    }
    EXPECT_EQ(one.rmse_a, two.rmse_a) << h;
    ASSERT_EQ(one.means.size(), two.means.size());
    for (std::size_t k = 0; k < one.means.size(); ++k) EXPECT_EQ(one.means[k], two.means[k]) << h;
  }
}

TEST(ImplicitSmoother, BadInput) {
  const Problem p = lin_problem();
  EXPECT_THROW(ImplicitSmoother(p, {.members = 10, .lag = 0}), InvalidArgument);
  EXPECT_THROW(ImplicitSmoother(p, {.members = 1, .lag = 2}), InvalidArgument);
  EXPECT_THROW(ImplicitSmoother(p, {.members = 10, .lag = 2, .inflation = 0.5}), InvalidArgument);
  EXPECT_THROW(ImplicitSmoother(p, {.members = 10, .lag = 2, .starts = 0}), InvalidArgument);
  for (const double h : {0.0, -0.5, 1.5, std::nan("")})
    EXPECT_THROW(ImplicitSmoother(p, {.members = 10, .lag = 2, .bandwidth = h}), InvalidArgument)
        << h;
  Problem noisy = p;
  noisy.Q = MatrixXd::Identity(3, 3);
  EXPECT_THROW(ImplicitSmoother(noisy, {.members = 10, .lag = 2}), InvalidArgument);
  ImplicitSmoother s(p, {.members = 10, .lag = 2});
  EXPECT_THROW(s.assimilate(VectorXd::Zero(2)), InvalidArgument);  // before initialize
  s.initialize(VectorXd::Zero(3), MatrixXd::Identity(3, 3));
  EXPECT_THROW(s.assimilate(Eigen::Vector2d(1.0, std::nan(""))), InvalidArgument);
  EXPECT_THROW(s.assimilate(VectorXd::Zero(3)), InvalidArgument);
}

}  // namespace
}  // namespace implicit::da
