// The implicit-sampling kernel: factor models, the one Newton loop (with Gauss-Newton fallback
// and equality constraints), the generic linear and random maps and the one log-weight formula;
// and core's dense entry points (minimize, linear_map_sample, random_map_sample) as the kernel.
// Oracles are closed forms (quadratics, Gaussians) and the dense Eigen factorisation.

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "implicit/core/banded.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/linear_map.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/random_map.hpp"
#include "implicit/core/target.hpp"

namespace {
using namespace implicit;

Mat<5> spd5() {
  Mat<5> a;
  a << 4, 1, 0, 0.5, 0, 1, 3, 0.2, 0, 0, 0, 0.2, 2, 0.3, 0.1, 0.5, 0, 0.3, 5, 1, 0, 0, 0.1, 1, 2;
  return a;
}

// Every factor model gives log det L = 1/2 log det H, H^-1 v, and L^-T with L^-T L^-1 = H^-1.
template <typename Factor, int N>
void expect_factor_matches_dense(Factor& factor, const typename Factor::Hessian& h,
                                 const Eigen::MatrixXd& dense) {
  ASSERT_TRUE(factor.compute(h));
  const Eigen::LLT<Eigen::MatrixXd> ref(dense);
  const double ref_log_det = 0.5 * std::log(dense.determinant());
  EXPECT_NEAR(factor.log_det_L(), ref_log_det, 1e-12 * (1.0 + std::abs(ref_log_det)));
  const Eigen::MatrixXd inverse = ref.solve(Eigen::MatrixXd::Identity(dense.rows(), dense.cols()));
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(dense.rows(), dense.cols());
  for (int k = 0; k < dense.rows(); ++k) {
    typename Factor::Vector v = Eigen::VectorXd::Unit(dense.rows(), k);
    factor.solve_in_place(v);
    EXPECT_LT((Eigen::VectorXd(v) - inverse.col(k)).cwiseAbs().maxCoeff(), 1e-12);
    typename Factor::Vector u = Eigen::VectorXd::Unit(dense.rows(), k);
    factor.upper_solve_in_place(u);  // column k of L^-T
    cov += Eigen::VectorXd(u) * Eigen::VectorXd(u).transpose();
  }
  EXPECT_LT((cov - inverse).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(GaussianFactor, EveryModelMatchesTheDenseFactorisation) {
  const Mat<5> a5 = spd5();
  DenseFactor<5> d5;
  expect_factor_matches_dense<DenseFactor<5>, 5>(d5, a5, a5);
  SmallFactor<5> s5;
  expect_factor_matches_dense<SmallFactor<5>, 5>(s5, a5, a5);
  DenseFactor<Eigen::Dynamic> dd;
  expect_factor_matches_dense<DenseFactor<Eigen::Dynamic>, Eigen::Dynamic>(dd, a5, a5);
  const Mat<3> a3 = a5.topLeftCorner<3, 3>();
  SmallFactor<3> s3;
  expect_factor_matches_dense<SmallFactor<3>, 3>(s3, a3, a3);
  BlockTridiagonal<2> b(3);
  b.diagonal[0] << 4, 1, 1, 3;
  b.diagonal[1] << 5, 0.5, 0.5, 2;
  b.diagonal[2] << 3, -1, -1, 4;
  b.subdiagonal[0] << 0.3, 0.1, -0.2, 0.4;
  b.subdiagonal[1] << 0.5, 0.0, 0.1, -0.3;
  BandedFactor<2> bc;
  expect_factor_matches_dense<BandedFactor<2>, Eigen::Dynamic>(bc, b, b.to_dense());
}

TEST(GaussianFactor, RejectsIndefiniteAndNonFinite) {
  Mat<3> a = Mat<3>::Identity();
  a(2, 2) = -1.0;
  SmallFactor<3> s3;
  EXPECT_FALSE(s3.compute(a));
  DenseFactor<3> d3;
  EXPECT_FALSE(d3.compute(a));
  a(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(s3.compute(a));
  EXPECT_FALSE(d3.compute(a));
}

// F(x) = 1/2 (x - a)^T H (x - a) + c: Newton lands on a in one step with any factor.
struct DenseQuadratic {
  Mat<5> h = spd5();
  Vec<5> a = (Vec<5>() << 1, -2, 0.5, 3, -1).finished();
  double evaluate(const Vec<5>& x, Vec<5>* g, Mat<5>* hess) const {
    const Vec<5> d = x - a;
    if (g) *g = h * d;
    if (hess) *hess = h;
    return 0.5 * d.dot(h * d) + 2.0;
  }
};

TEST(NewtonMinimize, QuadraticInOneStepWithDenseAndSmallFactors) {
  const DenseQuadratic q;
  for (int variant = 0; variant < 2; ++variant) {
    const auto check = [&](const auto& r) {
      EXPECT_EQ(r.status, MinimizeStatus::kConverged);
      EXPECT_EQ(r.iterations, 1);
      EXPECT_LT((r.x - q.a).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_NEAR(r.value, 2.0, 1e-14);
      EXPECT_TRUE(r.factor_ok);
      EXPECT_TRUE(r.exact_factor);
      EXPECT_NEAR(r.factor.log_det_L(), 0.5 * std::log(q.h.determinant()), 1e-12);
    };
    if (variant == 0)
      check(newton_minimize<DenseFactor<5>>(q, Vec<5>::Zero()));
    else
      check(newton_minimize<SmallFactor<5>>(q, Vec<5>::Zero()));
  }
}

// Least squares with an indefinite exact Hessian at the start: F = 1/2 r(x)^2 + 1/2 x^T D x / 100,
// r = |x|^2 - 4 (a sphere), D = diag(1, 2, 3). Offers the Gauss-Newton Hessian J^T J + D/100.
// Stationary points: 2 r x + D x / 100 = 0, so one non-zero coordinate; the minimum is on the
// first axis with r = -1/200, x0^2 = 4 - 1/200, where H = diag(4 x0^2, 1/100, 2/100) is SPD.
struct Sphere {
  double evaluate(const Vec<3>& x, Vec<3>* g, Mat<3>* h, Mat<3>* gn = nullptr) const {
    const Vec<3> d(1.0, 2.0, 3.0);
    const double r = x.squaredNorm() - 4.0;
    const Vec<3> j = 2.0 * x;
    if (g) *g = r * j + d.cwiseProduct(x) / 100.0;
    const Mat<3> jj = j * j.transpose() + Mat<3>(d.asDiagonal()) / 100.0;
    if (gn) *gn = jj;
    if (h) *h = jj + 2.0 * r * Mat<3>::Identity();
    return 0.5 * r * r + 0.5 * x.dot(d.cwiseProduct(x)) / 100.0;
  }
};

TEST(NewtonMinimize, GaussNewtonFallbackReachesTheMinimumAndFactorsTheExactHessianThere) {
  NewtonOptions o;
  o.fallback = HessianFallback::kGaussNewton;
  const Vec<3> start(0.5, 0.1, 0.05);
  Mat<3> h0;
  Sphere{}.evaluate(start, nullptr, &h0);
  ASSERT_FALSE(SmallFactor<3>().compute(h0));  // the fallback is needed at the start
  const auto r = newton_minimize<SmallFactor<3>>(Sphere{}, start, o);
  EXPECT_EQ(r.status, MinimizeStatus::kConverged);
  EXPECT_NEAR(r.x(0) * r.x(0), 4.0 - 1.0 / 200.0, 1e-9);
  EXPECT_LT(r.x.tail<2>().cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE(r.exact_factor);
  EXPECT_LT(r.gradient.cwiseAbs().maxCoeff(), 1e-9);
}

// Without damping, a point where neither the exact nor the Gauss-Newton Hessian factors ends the
// minimisation there (x is kept); with damping (the default) Levenberg carries it to the minimum.
TEST(NewtonMinimize, WithoutDampingAPointWithNoSpdHessianIsReported) {
  struct Saddle {  // F = x0^4 / 4 - x0^2 / 2 + |x_12|^2 / 2: H_00 = -1 at 0, minima at x0 = +-1
    double evaluate(const Vec<3>& x, Vec<3>* g, Mat<3>* h, Mat<3>* gn = nullptr) const {
      if (g) *g = Vec<3>(x(0) * x(0) * x(0) - x(0), x(1), x(2));
      if (h) *h = Vec<3>(3.0 * x(0) * x(0) - 1.0, 1.0, 1.0).asDiagonal();
      if (gn) *gn = Vec<3>(-1.0, 1.0, 1.0).asDiagonal();  // not SPD either
      return 0.25 * std::pow(x(0), 4) - 0.5 * x(0) * x(0) + 0.5 * x.tail<2>().squaredNorm();
    }
  };
  NewtonOptions o;
  o.fallback = HessianFallback::kGaussNewton;
  const Vec<3> start(0.1, 0.5, -0.5);
  o.damping = false;
  const auto stopped = newton_minimize<SmallFactor<3>>(Saddle{}, start, o);
  EXPECT_EQ(stopped.status, MinimizeStatus::kNotPositiveDefinite);
  EXPECT_FALSE(stopped.factor_ok);
  EXPECT_EQ(stopped.x, start);
  EXPECT_EQ(stopped.iterations, 0);
  o.damping = true;
  const auto damped = newton_minimize<SmallFactor<3>>(Saddle{}, start, o);
  EXPECT_EQ(damped.status, MinimizeStatus::kConverged);
  EXPECT_NEAR(std::abs(damped.x(0)), 1.0, 1e-9);
  EXPECT_TRUE(damped.exact_factor);
}

// A banded path F = sum_i 1/2 (y_i - y_{i-1})^2 + sum_i cosh(y_i - t_i) with equalities
// y_2 = 0.5 and y_5 = -1: the KKT conditions grad F + C nu = 0, C^T y = e are the oracle.
struct CoshChain {
  int n = 8;
  int num_blocks() const { return n; }
  double target(int i) const { return 0.3 * i - 1.0; }
  double evaluate(const Eigen::VectorXd& y, Eigen::VectorXd* g, BlockTridiagonal<1>* h) const {
    double v = 0.0;
    if (g) g->setZero(n);
    if (h) h->resize(n);
    for (int i = 0; i < n; ++i) {
      const double d = y(i) - target(i);
      v += std::cosh(d);
      if (g) (*g)(i) += std::sinh(d);
      if (h) h->diagonal[i](0, 0) += std::cosh(d);
      if (i == 0) continue;
      const double s = y(i) - y(i - 1);
      v += 0.5 * s * s;
      if (g) {
        (*g)(i) += s;
        (*g)(i - 1) -= s;
      }
      if (h) {
        h->diagonal[i](0, 0) += 1.0;
        h->diagonal[i - 1](0, 0) += 1.0;
        h->subdiagonal[i - 1](0, 0) -= 1.0;
      }
    }
    return v;
  }
};

TEST(NewtonMinimize, EqualityConstraintsOnABandedFactorMeetTheKktConditions) {
  const CoshChain f;
  EqualityConstraints<Eigen::Dynamic> c;
  c.C = Eigen::MatrixXd::Zero(f.n, 2);
  c.C(2, 0) = 1.0;
  c.C(5, 1) = 1.0;
  c.e = Eigen::Vector2d(0.5, -1.0);
  const auto r = newton_minimize<BandedFactor<1>>(f, Eigen::VectorXd::Zero(f.n), {}, &c);
  ASSERT_EQ(r.status, MinimizeStatus::kConverged);
  EXPECT_NEAR(r.x(2), 0.5, 1e-12);
  EXPECT_NEAR(r.x(5), -1.0, 1e-12);
  Eigen::VectorXd g;
  f.evaluate(r.x, &g, nullptr);
  EXPECT_LT((g + c.C * r.multipliers).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(std::abs(r.multipliers(0)), 1e-3);  // the constraints are active
  // Unconstrained on the same factor: the gradient vanishes.
  const auto u = newton_minimize<BandedFactor<1>>(f, Eigen::VectorXd::Zero(f.n));
  ASSERT_EQ(u.status, MinimizeStatus::kConverged);
  EXPECT_LT(u.gradient.cwiseAbs().maxCoeff(), 1e-10);
}

TEST(NewtonMinimize, NonFiniteStartIsReportedNotThrown) {
  struct Inf {
    double evaluate(const Vec<3>&, Vec<3>* g, Mat<3>* h) const {
      if (g) g->setZero();
      if (h) h->setIdentity();
      return std::numeric_limits<double>::infinity();
    }
  };
  const auto r = newton_minimize<SmallFactor<3>>(Inf{}, Vec<3>::Zero());
  EXPECT_EQ(r.status, MinimizeStatus::kNonFinite);
  EXPECT_FALSE(r.factor_ok);
}

// For a Gaussian target F = 1/2 (x - a)^T H (x - a) + c both maps give every sample the weight
// Z = (2 pi)^{m/2} det(H)^{-1/2} e^{-c} exactly, with every factor model.
TEST(ImplicitLogWeight, BothMapsAreExactForGaussiansWithEveryFactor) {
  const DenseQuadratic q;
  const double log_z = 2.5 * kLog2Pi - 0.5 * std::log(q.h.determinant()) - 2.0;
  SmallFactor<5> small;
  ASSERT_TRUE(small.compute(q.h));
  DenseFactor<5> dense;
  ASSERT_TRUE(dense.compute(q.h));
  const Vec<5> xis[] = {(Vec<5>() << 0.3, -1.2, 0.7, 2.0, -0.4).finished(),
                        (Vec<5>() << -2.5, 0.1, 0.0, 0.3, 1.1).finished()};
  for (const Vec<5>& xi : xis) {
    Vec<5> x1, x2, x3;
    EXPECT_NEAR(linear_map(q, q.a, small, xi, x1), log_z, 1e-12);
    double lw = 0.0;
    ASSERT_EQ(random_map(q, q.a, 2.0, dense, xi, x2, lw), RayStatus::kOk);
    EXPECT_NEAR(lw, log_z, 1e-10);
    // Same sample from the linear map (the ray's root is lambda = |xi| for a Gaussian).
    EXPECT_LT((x1 - x2).cwiseAbs().maxCoeff(), 1e-10);
    const Mat<5> L = dense.matrixL();
    EXPECT_NEAR(linear_map(q, q.a, LowerFactorView<5>(L, dense.log_det_L()), xi, x3), log_z, 1e-12);
  }
}

TEST(ImplicitLogWeight, OutsideTheSupportIsZeroWeight) {
  EXPECT_EQ(implicit_log_weight(3, 1.0, std::numeric_limits<double>::infinity(), 0.0),
            -std::numeric_limits<double>::infinity());
  EXPECT_EQ(implicit_log_weight(3, 1.0, std::numeric_limits<double>::quiet_NaN(), 0.0),
            -std::numeric_limits<double>::infinity());
}

TEST(RandomMapRay, AJumpOverTheLevelIsReportedNotARoot) {
  // g = lambda^2 / 2 - 2 below lambda = 1, +inf above: the level 2 lies beyond the jump.
  auto g = [](double l, double* s) {
    if (s) *s = l;
    return l < 1.0 ? 0.5 * l * l - 2.0 : std::numeric_limits<double>::infinity();
  };
  double lambda = 0.0, slope = 0.0;
  EXPECT_EQ(solve_random_map_ray(g, 4.0, 2.0, lambda, slope), RayStatus::kJump);
  // Without the jump the root is lambda = 2.
  auto smooth = [](double l, double* s) {
    if (s) *s = l;
    return 0.5 * l * l - 2.0;
  };
  ASSERT_EQ(solve_random_map_ray(smooth, 4.0, 2.0, lambda, slope), RayStatus::kOk);
  // The solver stops at a relative bracket width of 1e-12 with hi <= 4 here: |error| <= 4e-12.
  EXPECT_NEAR(lambda, 2.0, 4e-12);
  EXPECT_NEAR(slope, 2.0, 4e-12);
}

// F is +inf on every lambda > 0 while g(0) = -rho / 2 < 0: F jumps over the level at 0+. The
// bracket [0, hi] can only shrink onto 0, where no relative tolerance is met; the solver stops
// when hi <= 1e-12 sqrt(rho) (about 40 halvings) and reports the jump, not a failure.
TEST(RandomMapRay, InfiniteOnTheWholeRayIsAJumpAtZero) {
  int calls = 0;
  auto wall = [&](double, double* s) {
    ++calls;
    if (s) *s = 0.0;
    return std::numeric_limits<double>::infinity();
  };
  double lambda = 0.0, slope = 0.0;
  EXPECT_EQ(solve_random_map_ray(wall, 4.0, 2.0, lambda, slope), RayStatus::kJump);
  EXPECT_LE(calls, 45);
  // A finite jump over the level at 0+ is not a wall: still not converged, after every iteration.
  calls = 0;
  auto step = [&](double l, double* s) {
    ++calls;
    if (s) *s = l;
    return 1.0 + 0.5 * l * l;
  };
  EXPECT_EQ(solve_random_map_ray(step, 4.0, 2.0, lambda, slope), RayStatus::kNotConverged);
  EXPECT_EQ(calls, 202);
}

// g = NaN outside the support is +inf: the same status, root and evaluations as the +inf variant
// (a NaN taken for "below the level" would push the bracket past the support).
TEST(RandomMapRay, NanOutsideTheSupportIsInfinite) {
  // F = lambda^2 / 2 up to an edge, outside beyond; the level puts the root at lambda = 2. With
  // the edge at 1.5 the ray jumps over the level; with the edge at 3 the root is found.
  std::vector<double> roots;
  std::vector<int> counts;
  for (double outside :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    for (double edge : {1.5, 3.0}) {
      int calls = 0;
      auto g = [&](double l, double* s) {
        ++calls;
        if (s) *s = l;
        return l > edge ? outside : 0.5 * l * l - 2.0;
      };
      double lambda = 0.0, slope = 0.0;
      const RayStatus st = solve_random_map_ray(g, 4.0, 2.0, lambda, slope);
      EXPECT_EQ(st, edge < 2.0 ? RayStatus::kJump : RayStatus::kOk) << outside << " " << edge;
      // The solver stops at a relative step of 1e-12: a few of those from the root.
      if (edge > 2.0) {
        EXPECT_NEAR(lambda, 2.0, 1e-11) << outside;
      }
      roots.push_back(lambda);
      counts.push_back(calls);
    }
  }
  // NaN and +inf take the same path, bit for bit.
  EXPECT_EQ(roots[0], roots[2]);
  EXPECT_EQ(roots[1], roots[3]);
  EXPECT_EQ(counts[0], counts[2]);
  EXPECT_EQ(counts[1], counts[3]);
}

// Rays with a root keep their iterates: the roots and evaluation counts recorded from the solver
// before the jump at 0 was recognised (x86-64, bit for bit; 4 ulps allow for contracted
// multiply-adds elsewhere). `steep` is approached by Newton from above (lo stays 0 until the
// last step), `flat` needs doublings of the bracket.
TEST(RandomMapRay, RaysWithARootKeepTheirIterates) {
  struct Case {
    double (*g)(double, double*);
    double root;
    int calls;
  };
  const Case cases[] = {
      {[](double l, double* s) {
         if (s) *s = 4.0 * std::exp(4.0 * l);
         return std::exp(4.0 * l) - 3.0;
       },
       0x1.193ea7aad030bp-2, 11},
      {[](double l, double* s) {
         if (s) *s = l + l * l * l;
         return 0.5 * l * l + 0.25 * l * l * l * l - 2.0;
       },
       0x1.6a09e667f3bcdp+0, 8},
      {[](double l, double* s) {
         if (s) *s = 0.02 * l;
         return 0.01 * l * l - 2.0;
       },
       0x1.c48c6001f299ep+3, 21},
  };
  for (const Case& c : cases) {
    int calls = 0;
    auto g = [&](double l, double* s) {
      ++calls;
      return c.g(l, s);
    };
    double lambda = 0.0, slope = 0.0;
    ASSERT_EQ(solve_random_map_ray(g, 4.0, 2.0, lambda, slope), RayStatus::kOk);
    EXPECT_DOUBLE_EQ(lambda, c.root);
    EXPECT_EQ(calls, c.calls);
  }
}

// F = 1/2 x^T H x + 2 on the half-space n^T x <= 0 and `outside` (+inf, or NaN for "no value")
// beyond: finite at the mode 0, which lies on the edge of the support. The mode is 0 so that
// x = lambda d leaves the half-space for every lambda > 0 however small (x = mu + lambda d with
// mu != 0 rounds back onto mu for tiny lambda, which lands F on its finite side).
template <int M>
struct HalfSpaceQuadratic {
  Mat<M> h;
  Vec<M> n;
  double outside;
  double evaluate(const Vec<M>& x, Vec<M>* g, Mat<M>* hess) const {
    if (g) *g = h * x;
    if (hess) *hess = h;
    return n.dot(x) <= 0.0 ? 0.5 * x.dot(h * x) + 2.0 : outside;
  }
};

// Of the rays xi and -xi from the mode, the one leaving the half-space sees F = +inf (or NaN) for
// every lambda > 0: kJump with weight 0. The other stays inside, where F is the Gaussian and the
// weight is Z = (2 pi)^{m/2} det(H)^{-1/2} e^{-2} exactly.
template <int M>
void expect_half_space_rays(const HalfSpaceQuadratic<M>& f, const Vec<M>& xi) {
  DenseFactor<M> factor;
  ASSERT_TRUE(factor.compute(f.h));
  const double log_z = 0.5 * M * kLog2Pi - 0.5 * std::log(f.h.determinant()) - 2.0;
  for (const Vec<M>& x0 : {Vec<M>(xi), Vec<M>(-xi)}) {
    Vec<M> d = x0;
    factor.upper_solve_in_place(d);  // the ray's direction (up to |xi|)
    ASSERT_NE(f.n.dot(d), 0.0);
    Vec<M> x;
    double lw = 0.0;
    const RayStatus status = random_map(f, Vec<M>::Zero().eval(), 2.0, factor, x0, x, lw);
    if (f.n.dot(d) > 0.0) {
      EXPECT_EQ(status, RayStatus::kJump);
      EXPECT_EQ(lw, -std::numeric_limits<double>::infinity());
    } else {
      ASSERT_EQ(status, RayStatus::kOk);
      EXPECT_NEAR(lw, log_z, 1e-10);
      EXPECT_LT((x - d).cwiseAbs().maxCoeff(), 1e-10);  // the linear map's point
    }
  }
}

TEST(CoreOnKernel, RandomMapLeavingTheSupportAtTheModeIsAJump) {
  for (const double outside :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    // 1-D: F = x^2 + 2 on x <= 0.
    const HalfSpaceQuadratic<1> f1{Mat<1>::Constant(2.0), Vec<1>::Constant(1.0), outside};
    expect_half_space_rays(f1, Vec<1>(Vec<1>::Constant(0.8)));
    // 5-D: a Gaussian on a half-space through its mode.
    const HalfSpaceQuadratic<5> f5{spd5(), (Vec<5>() << 1, -1, 0.5, 0, 2).finished(), outside};
    expect_half_space_rays(f5, (Vec<5>() << 0.3, -1.2, 0.7, 2.0, -0.4).finished());
    expect_half_space_rays(f5, (Vec<5>() << -2.5, 0.1, 0.0, 0.3, 1.1).finished());
  }
}

// minimize() is the kernel with the dense factor: the same iterates, bit for bit.
TEST(CoreOnKernel, MinimizeIsNewtonWithTheDenseFactor) {
  const auto f = make_autodiff_target<2>([](const auto& x) {
    const auto b = x(1) - x(0) * x(0);
    return (1.0 - x(0)) * (1.0 - x(0)) + 100.0 * (b * b);
  });
  const Vec<2> x0(-1.2, 1.0);
  const auto r = minimize(f, x0);
  const auto k = newton_minimize<DenseFactor<2>>(f, x0, NewtonOptions(MinimizeOptions{}));
  ASSERT_EQ(r.status, MinimizeStatus::kConverged);
  EXPECT_EQ(r.status, k.status);
  EXPECT_EQ(r.x, k.x);
  EXPECT_EQ(r.value, k.value);
  EXPECT_EQ(r.iterations, k.iterations);
  EXPECT_EQ(r.evaluations, k.evaluations);
}

// The dense samplers are the kernel's maps with the Laplace approximation's L: the same samples
// and weights as with the dense factor of the same Hessian.
TEST(CoreOnKernel, DenseSamplersAreTheKernelMaps) {
  const auto f = make_autodiff_target<2>([](const auto& x) {
    return 0.5 * (x(0) * x(0)) + 0.25 * (x(0) * x(0)) * (x(0) * x(0)) + x(1) * x(1);
  });
  const auto r = minimize(f, Vec<2>(0.5, -0.3));
  const auto lp = Laplace<2>::from(r);
  DenseFactor<2> dense;
  ASSERT_TRUE(dense.compute(r.hessian));
  for (const Vec<2>& xi : {Vec<2>(0.3, -1.2), Vec<2>(-2.5, 0.7)}) {
    Vec<2> x1, x2;
    EXPECT_NEAR(linear_map_sample(f, lp, xi, x1), linear_map(f, lp.mu, dense, xi, x2), 1e-12);
    EXPECT_LT((x1 - x2).cwiseAbs().maxCoeff(), 1e-12);
    double w1 = 0.0, w2 = 0.0;
    ASSERT_EQ(random_map_sample(f, lp, xi, x1, w1), RandomMapStatus::kOk);
    ASSERT_EQ(random_map(f, lp.mu, lp.phi, dense, xi, x2, w2), RayStatus::kOk);
    EXPECT_NEAR(w1, w2, 1e-12);
    EXPECT_LT((x1 - x2).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// F = |x|^2 / 2 inside the unit disc and +inf outside: for |xi| > 1 the level phi + |xi|^2 / 2
// lies beyond the jump, so no point of the ray maps there and the weight is exactly 0.
TEST(CoreOnKernel, RandomMapSampleReportsAJumpWithWeightZero) {
  const auto f = make_analytic_target<2>([](const Vec<2>& x, Vec<2>* g, Mat<2>* h) {
    if (g) *g = x;
    if (h) h->setIdentity();
    return x.squaredNorm() < 1.0 ? 0.5 * x.squaredNorm() : std::numeric_limits<double>::infinity();
  });
  const auto lp = Laplace<2>::make(Vec<2>::Zero(), 0.0, Mat<2>::Identity());
  Vec<2> x;
  double lw = 0.0;
  EXPECT_EQ(random_map_sample(f, lp, Vec<2>(1.5, 0.5), x, lw), RandomMapStatus::kJump);
  EXPECT_EQ(lw, -std::numeric_limits<double>::infinity());
  // Inside the disc the map is the identity and the weight that of the Gaussian, 2 pi.
  ASSERT_EQ(random_map_sample(f, lp, Vec<2>(0.3, 0.4), x, lw), RandomMapStatus::kOk);
  EXPECT_NEAR(lw, kLog2Pi, 1e-12);
  EXPECT_LT((x - Vec<2>(0.3, 0.4)).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
