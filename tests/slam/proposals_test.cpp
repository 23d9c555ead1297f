// The objectives of implicit SLAM against the oracles of spec §3.7 (Cases A, B, C), autodiff,
// and FastSLAM 2.0's linearised proposal against the closed-form optimal proposal.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "implicit/core/jet.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/mcl_objective.hpp"
#include "implicit/robot/ute_model.hpp"
#include "implicit/slam/proposals.hpp"

namespace implicit::slam {
namespace {

using robot::RangeBearingSensor;
using robot::UteModel;

// Spec §3.1 oracle: X_{n-1} = (10, 5, 0.3), encoder speed 3, steering 0.1.
struct Common {
  UteModel model;
  RangeBearingSensor sensor;
  Vec<3> f;
  Mat<3> sigma1;
  Common() {
    const Vec<3> x(10, 5, 0.3);
    const Vec<2> u(model.axle_speed(3.0, 0.1), 0.1);
    f = model.predict(x, u);
    sigma1 = model.process_covariance(x, u);
  }
};

void expect_rel(double got, double want, double rel, const char* what) {
  EXPECT_NEAR(got, want, rel * std::max(1.0, std::abs(want))) << what;
}

template <int N>
void expect_rel(const Eigen::Matrix<double, N, 1>& got, const std::vector<double>& want, double rel,
                const char* what) {
  for (int i = 0; i < N; ++i) expect_rel(got(i), want[static_cast<std::size_t>(i)], rel, what);
}

// F of spec §3.7 without its constant: the filter layer's pose objective that implicit SLAM uses
// (set_pose_objective), one term per landmark with the information S^-1 of its own S.
struct Term {
  Vec<2> landmark;
  Vec<2> z;
  Mat<2> s;
};
PoseObjective<> objective(const Common& c, const std::vector<Term>& terms) {
  PoseObjective<> F;
  const Mat<3> precision = c.sigma1.llt().solve(Mat<3>::Identity());
  F.reset(c.sensor, Mat<2>::Identity(), c.f, 0.5 * (precision + precision.transpose()), 0.0);
  for (const Term& t : terms) EXPECT_TRUE(F.add(t.landmark, t.z, t.s.inverse()));
  return F;
}

TEST(PoseObjective, CaseAOracle) {
  const Common c;
  const PoseObjective<> F = objective(
      c, {{Vec<2>(20, 12), Vec<2>(12.1682955572, 1.8806599794), c.sensor.noise_covariance()}});
  Vec<3> g;
  Mat<3> h, hgn;
  const double v = F.evaluate(c.f, &g, &h, &hgn);
  expect_rel(v, 0.014014336680, 1e-8, "F(f)");
  // The oracle's z is rounded to 1e-10; the gradient amplifies that by up to |J^T Sigma2^-1| ~
  // 1/sigma2 = 1146 (bearing), so gradients at Case A agree to ~6e-8 only: tolerance 2e-7.
  const Vec<3> want_g(0.5634353514, 0.4845133583, 0.8856871421);
  EXPECT_LT((g - want_g).cwiseAbs().maxCoeff(), 2e-7);
  const double want_h[3][3] = {{504.2632900481, -1075.0720121249, 4463.5484653852},
                               {-1075.0720121249, 3660.1271445824, -14283.2532646218},
                               {4463.5484653852, -14283.2532646218, 58216.5213328328}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) expect_rel(h(i, j), want_h[i][j], 1e-8, "hess F(f)");
  const Vec<3> x2 = c.f + Vec<3>(0.2, -0.1, 0.01);
  expect_rel(F.evaluate(x2, &g, &h, &hgn), 76.093242330183, 1e-8, "F(f + d)");
  const Vec<3> want_g2(253.5311514905, -723.3752344939, 2903.9233431589);
  EXPECT_LT((g - want_g2).cwiseAbs().maxCoeff(), 2e-7);
  const filter::PoseMinimum lp =
      newton_minimize<SmallFactor<3>>(F, c.f, pose_newton_options(50, 1e-24));
  ASSERT_TRUE(filter::usable(lp) && lp.converged());
  expect_rel<3>(lp.x, {10.0667353158, 5.028063506, 0.3018870747}, 1e-9, "minimiser");
  expect_rel(F.evaluate(lp.x), 0.011911716008, 1e-8, "phi");
  expect_rel(lp.factor.log_det_L(), 10.545986532115, 1e-9, "log det L");
  EXPECT_NEAR(lp.factor.matrixL()(1, 0), -47.874846178, 1e-7);
}

TEST(PoseObjective, CaseBOracleTwoLandmarks) {
  const Common c;
  const PoseObjective<> F =
      objective(c, {{Vec<2>(20, 12), Vec<2>(12.3, 1.85), c.sensor.noise_covariance()},
                    {Vec<2>(11, 17), Vec<2>(12.1, 2.74), c.sensor.noise_covariance()}});
  const Vec<3> xt = c.f + Vec<3>(0.1, -0.05, 0.02);
  Vec<3> g;
  Mat<3> h, hgn;
  expect_rel(F.evaluate(xt, &g, &h, &hgn), 47.977334867179, 1e-8, "F(x_t)");
  expect_rel<3>(g, {198.8364716097, -575.5285795415, 2279.2775630361}, 1e-8, "grad");
  expect_rel(h(0, 0), 512.1047008408, 1e-8, "H11");
  expect_rel(h(0, 1), -1074.0587112778, 1e-8, "H12");
  expect_rel(h(2, 2), 59362.4369230944, 1e-8, "H33");
  const filter::PoseMinimum lp =
      newton_minimize<SmallFactor<3>>(F, c.f, pose_newton_options(50, 1e-24));
  ASSERT_TRUE(filter::usable(lp));
  expect_rel<3>(lp.x, {10.0180469054, 5.0788693051, 0.3187026551}, 1e-9, "minimiser");
  expect_rel(F.evaluate(lp.x), 0.543789188458, 1e-8, "phi");
  expect_rel(lp.factor.log_det_L(), 10.869741220601, 1e-9, "log det L");
}

// (B) uses a full innovation covariance S = H_m P H_m^T + Sigma2: check the analytic gradient and
// Hessian against second-order autodiff at random points (spec §3.7 asks 1e-9 relative for FD;
// autodiff is exact up to round-off).
TEST(PoseObjective, GradientAndHessianMatchAutodiffWithFullCovariance) {
  const Common c;
  Mat<2> s;
  s << 0.09, 0.004, 0.004, 0.002;
  const std::vector<Term> terms = {{Vec<2>(20, 12), Vec<2>(12.3, 1.85), s},
                                   {Vec<2>(11, 17), Vec<2>(12.1, 2.74), s}};
  const PoseObjective<> F = objective(c, terms);
  const Mat<2> s_inv = s.inverse();  // test only: explicit inverse as an independent oracle
  const Mat<3> p1 = c.sigma1.inverse();
  auto functor = [&](const auto& x) {
    using J = typename std::decay_t<decltype(x)>::Scalar;
    using std::atan2;
    using std::sqrt;
    J val = J(0.0, 3);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) val = val + 0.5 * p1(i, k) * (x(i) - c.f(i)) * (x(k) - c.f(k));
    for (const auto& t : terms) {
      const J dx = x(0) - t.landmark(0), dy = x(1) - t.landmark(1);
      const J r = sqrt(dx * dx + dy * dy);
      // The bearing residual near zero: no wrap needed at these points (checked below).
      const J b = atan2(-dy, -dx) - x(2) + kPi / 2.0 - t.z(1);
      const J e0 = r - t.z(0);
      val = val + 0.5 * (s_inv(0, 0) * e0 * e0 + 2.0 * s_inv(0, 1) * e0 * b + s_inv(1, 1) * b * b);
    }
    return val;
  };
  Rng rng({5, 0, 0, purpose::kUser});
  for (int trial = 0; trial < 10; ++trial) {
    const Vec<3> x = c.f + 0.2 * rng.normal_vector<3>().cwiseProduct(Vec<3>(1, 1, 0.1));
    Vec<3> g;
    Mat<3> h, hgn;
    const double v = F.evaluate(x, &g, &h, &hgn);
    const auto [va, ga, ha] = autodiff_hessian<3>(functor, x);
    EXPECT_NEAR(v, va, 1e-10 * (1 + std::abs(va)));
    EXPECT_LT((g - ga).norm(), 1e-9 * (1 + ga.norm()));
    EXPECT_LT((h - ha).norm(), 1e-9 * (1 + ha.norm()));
  }
}

// set_pose_objective builds F with its constant: 1/2 log det(2 pi Sigma1) + sum_i 1/2 log det(2
// pi S_i), S_i = Sigma2 for (A) and H_m P_i H_m^T + Sigma2 at f for (B) (closed forms here).
TEST(PoseObjective, SetPoseObjectiveHasTheConstantAndTheTermsOfAAndB) {
  const Common c;
  const Eigen::LLT<Mat<3>> llt1(c.sigma1);
  std::vector<KnownLandmark> known(2);
  known[0].mean = Vec<2>(20, 12);
  known[0].z = Vec<2>(12.3, 1.85);
  known[0].cov << 0.5, 0.1, 0.1, 0.3;
  known[1].mean = Vec<2>(11, 17);
  known[1].z = Vec<2>(12.1, 2.74);
  known[1].cov << 0.2, 0.0, 0.0, 0.2;
  const Vec<3> x = c.f + Vec<3>(0.1, -0.05, 0.02);
  for (bool point : {true, false}) {
    PoseObjective<> F;
    ASSERT_TRUE(set_pose_objective(F, c.sensor, c.f, llt1, known, point));
    std::vector<Term> terms;
    double constant = 0.5 * std::log((2.0 * kPi * c.sigma1).determinant());
    for (const KnownLandmark& k : known) {
      Mat<2> s = c.sensor.noise_covariance();
      if (!point) {
        const Mat<2> hm = c.sensor.jacobian_landmark(c.f, k.mean);
        s += hm * k.cov * hm.transpose();
      }
      terms.push_back({k.mean, k.z, s});
      constant += 0.5 * std::log((2.0 * kPi * s).determinant());
    }
    EXPECT_NEAR(F.constant(), constant, 1e-12 * std::abs(constant)) << point;
    const double want = objective(c, terms).evaluate(x) + constant;
    EXPECT_NEAR(F.evaluate(x), want, 1e-12 * std::abs(want)) << point;
  }
  // More landmarks than the objective holds, or an S that is not SPD: refused.
  std::vector<KnownLandmark> many(kMaxKnownPerStep + 1, known[0]);
  PoseObjective<> F;
  EXPECT_FALSE(set_pose_objective(F, c.sensor, c.f, llt1, many, true));
  known[0].cov << 1.0, 0.0, 0.0, -1e9;
  EXPECT_FALSE(set_pose_objective(F, c.sensor, c.f, llt1, known, false));
}

TEST(NewLandmarkObjective, CaseCOracle) {
  const Common c;
  const Vec<2> z(12.1682955572, 1.8806599794);
  const NewLandmarkObjective F(c.f, c.sigma1, z, c.sensor.noise_covariance());
  ASSERT_TRUE(F.ok());
  const Vec<5> mu = F.minimizer();
  expect_rel(mu(3), 20.0248635998, 1e-9, "g1");
  expect_rel(mu(4), 12.0289342712, 1e-9, "g2");
  Vec<5> p;
  p << c.f + Vec<3>(0.05, -0.03, 0.01), mu.tail<2>() + Vec<2>(0.3, -0.2);
  Vec<5> g;
  Mat<5> h;
  expect_rel(F.evaluate(p, &g, &h), 14.040496789249, 1e-8, "F(p)");
  expect_rel<5>(g, {98.4755668154, -305.7593641332, 1265.2714928527, 3.5437226135, -1.3390790577},
                1e-8, "grad F(p)");
  const double want[5][5] = {
      {504.30863582, -1075.1022170, 4465.9122313, -15.990423325, -5.7430125594},
      {-1075.1022170, 3660.1366578, -14283.004740, -5.7430125594, -11.789873186},
      {4465.9122313, -14283.004740, 58216.521333, 51.889960588, -77.573077479},
      {-15.990423325, -5.7430125594, 51.889960588, 15.990423325, 5.7430125594},
      {-5.7430125594, -11.789873186, -77.573077479, 5.7430125594, 11.789873186}};
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) expect_rel(h(i, j), want[i][j], 1e-8, "hess F(p)");
  // At the minimiser: F = 0, grad = 0, log det L by the closed form of spec §3.5.
  Vec<5> g0;
  EXPECT_NEAR(F.evaluate(mu, &g0, nullptr), 0.0, 1e-12);
  EXPECT_LT(g0.cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::LLT<Mat<5>> llt(F.hessian_at_minimizer());
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Mat<5> l = llt.matrixL();
  const double log_det_l = l.diagonal().array().log().sum();
  expect_rel(log_det_l, 11.625735443238, 1e-9, "log det L");
  const double closed = -0.5 * std::log(c.sigma1.determinant()) -
                        0.5 * std::log(c.sensor.noise_covariance().determinant()) - std::log(z(0));
  EXPECT_NEAR(log_det_l, closed, 1e-9);
  // The x-marginal of H^-1 is Sigma1 exactly; the theta-marginal is the oracle's.
  const Mat<5> cov = llt.solve(Mat<5>::Identity());
  EXPECT_LT((cov.topLeftCorner<3, 3>() - c.sigma1).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(cov(3, 3), 0.6376959687, 1e-9);
  EXPECT_NEAR(cov(3, 4), -0.9066236254, 1e-9);
  EXPECT_NEAR(cov(4, 4), 1.4697472995, 1e-9);
}

// FastSLAM 2.0: the proposal must be N(mu_x, Sigma_x) with Sigma_x = (H_x^T Q^-1 H_x +
// Sigma1^-1)^-1, mu_x = f + Sigma_x H_x^T Q^-1 nu, and the weight log N(nu; 0, H_x Sigma1 H_x^T +
// Q) (the pose term included). Oracle: the textbook formulas with explicit inverses, for one and
// for two detections (stacked).
TEST(LinearizedProposal, EqualsClosedFormOptimalProposal) {
  const Common c;
  std::vector<KnownLandmark> known(2);
  known[0].mean = Vec<2>(20, 12);
  known[0].z = Vec<2>(12.3, 1.85);
  known[0].cov << 0.04, 0.01, 0.01, 0.03;
  known[1].mean = Vec<2>(11, 17);
  known[1].z = Vec<2>(12.1, 2.74);
  known[1].cov << 0.02, -0.005, -0.005, 0.05;
  const Eigen::LLT<Mat<3>> llt1(c.sigma1);
  for (std::size_t count : {std::size_t{1}, std::size_t{2}}) {
    const std::span<const KnownLandmark> ks(known.data(), count);
    const LinearizedProposal lp = linearized_optimal_proposal(c.sensor, c.f, llt1, ks);
    ASSERT_TRUE(lp.ok);
    const auto m = static_cast<Eigen::Index>(2 * count);
    Eigen::MatrixXd hx(m, 3), q = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd nu(m);
    for (std::size_t i = 0; i < count; ++i) {
      const auto r = static_cast<Eigen::Index>(2 * i);
      hx.middleRows<2>(r) = c.sensor.jacobian_pose(c.f, ks[i].mean);
      const Mat<2> hm = c.sensor.jacobian_landmark(c.f, ks[i].mean);
      q.block<2, 2>(r, r) = c.sensor.noise_covariance() + hm * ks[i].cov * hm.transpose();
      nu.segment<2>(r) = -RangeBearingSensor::residual(c.sensor.predict(c.f, ks[i].mean), ks[i].z);
    }
    const Mat<3> sigma_x = (hx.transpose() * q.inverse() * hx + c.sigma1.inverse()).inverse();
    const Vec<3> mu_x = c.f + sigma_x * hx.transpose() * q.inverse() * nu;
    const Eigen::MatrixXd s = hx * c.sigma1 * hx.transpose() + q;
    const double log_n = -0.5 * static_cast<double>(m) * kLog2Pi - 0.5 * std::log(s.determinant()) -
                         0.5 * nu.dot(s.inverse() * nu);
    EXPECT_LT((lp.mean - mu_x).cwiseAbs().maxCoeff(), 1e-10);
    const Mat<3> cov = (lp.L * lp.L.transpose()).inverse();
    EXPECT_LT(((cov - sigma_x).array() / sigma_x.cwiseAbs().array().max(1e-12)).abs().maxCoeff(),
              1e-7);
    EXPECT_NEAR(lp.log_weight, log_n, 1e-8 * (1 + std::abs(log_n)));
  }
}

}  // namespace
}  // namespace implicit::slam
