// Block-tridiagonal Cholesky and banded Newton (include/implicit/core/banded.hpp) against dense
// Eigen results.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "implicit/core/banded.hpp"
#include "implicit/core/rng.hpp"

using implicit::BlockTridiagonal;
using implicit::BlockTridiagonalCholesky;

namespace {
template <int B>
BlockTridiagonal<B> random_spd(int n, std::uint64_t seed) {
  implicit::Rng rng({seed, 0, 0, 1});
  BlockTridiagonal<B> h(n);
  for (int i = 0; i < n; ++i) {
    implicit::Mat<B> a;
    rng.fill_normal(a);
    h.diagonal[i] = a * a.transpose() + 4.0 * B * implicit::Mat<B>::Identity();
    if (i + 1 < n) rng.fill_normal(h.subdiagonal[i]);
  }
  return h;
}
}  // namespace

TEST(Banded, MatchesDenseCholesky) {
  const auto h = random_spd<2>(7, 3);
  const Eigen::MatrixXd d = h.to_dense();
  const Eigen::LLT<Eigen::MatrixXd> llt(d);
  ASSERT_EQ(llt.info(), Eigen::Success);
  BlockTridiagonalCholesky<2> c(h);
  ASSERT_TRUE(c.ok());
  const Eigen::MatrixXd L = llt.matrixL();
  EXPECT_NEAR(c.log_det_L(), L.diagonal().array().log().sum(), 1e-12);
  implicit::Rng rng({4, 0, 0, 1});
  Eigen::VectorXd b(14);
  rng.fill_normal(b);
  EXPECT_LT((c.solve(b) - llt.solve(b)).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::VectorXd v = b;
  c.upper_solve_in_place(v);  // L^{-T} b (the Cholesky factor is unique)
  const Eigen::VectorXd ref = L.transpose().triangularView<Eigen::Upper>().solve(b);
  EXPECT_LT((v - ref).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((c.upper_multiply(v) - b).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((h.multiply(b) - d * b).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Banded, RejectsIndefinite) {
  auto h = random_spd<1>(5, 2);
  h.diagonal[3](0, 0) = -1.0;
  BlockTridiagonalCholesky<1> c;
  EXPECT_FALSE(c.compute(h));
  EXPECT_FALSE(c.ok());
}

namespace {
// A non-convex chain: sum (y_i - y_{i-1})^2 / 2 + sum cos(y_i), y_0 = 1 (tridiagonal Hessian).
struct Chain {
  static constexpr int Block = 1;
  int n = 30;
  int num_blocks() const { return n; }
  double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* g, BlockTridiagonal<1>* h) const {
    double f = 0.0, prev = 1.0;
    if (g) g->setZero(n);
    if (h) h->resize(n);
    for (int i = 0; i < n; ++i) {
      const double d = y(i) - prev;
      f += 0.5 * d * d + std::cos(y(i));
      if (g) {
        (*g)(i) += d - std::sin(y(i));
        if (i > 0) (*g)(i - 1) -= d;
      }
      if (h) {
        h->diagonal[i](0, 0) += 1.0 - std::cos(y(i));
        if (i > 0) {
          h->diagonal[i - 1](0, 0) += 1.0;
          h->subdiagonal[i - 1](0, 0) = -1.0;
        }
      }
      prev = y(i);
    }
    return f;
  }
};
}  // namespace

TEST(Banded, NewtonConvergesOnNonConvexChain) {
  Chain c;
  const auto r = implicit::minimize_banded(c, Eigen::VectorXd::Zero(c.n));
  ASSERT_TRUE(r.converged()) << implicit::to_string(r.status);
  EXPECT_LT(r.gradient.cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE(r.factor.ok());
  // Wrong size input: a status, not an exception.
  EXPECT_EQ(implicit::minimize_banded(c, Eigen::VectorXd::Zero(3)).status,
            implicit::MinimizeStatus::kNonFinite);
}
