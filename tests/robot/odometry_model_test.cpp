// The odometry motion model: the decomposition is exact, the variances are the alpha formulas
// (checked by hand for simple motions), J matches finite differences, and the Gaussian form's
// covariance matches the exact sampler's in a small-noise regime (tolerances from the standard
// error of a sample covariance).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/odometry_model.hpp"

namespace implicit::robot {
namespace {

constexpr OdometryAlphas kDistinct{.alpha1 = 0.1, .alpha2 = 0.2, .alpha3 = 0.3, .alpha4 = 0.4};

// Steps of every kind: forward, backward, sideways, turning on the spot, tiny, a heading jump.
const std::vector<OdometryDelta>& steps() {
  static const std::vector<OdometryDelta> s = {
      {0.4, 0.15, 0.35},  {-0.6, 0.1, -0.2}, {0.0, 0.3, 0.0},   {0.0, 0.0, 1.2},
      {2e-3, -1e-3, 0.0}, {0.0, 0.0, 0.0},   {0.5, -0.5, 6.0},  {-1.0, -1e-3, 3.0},
      {1e-12, 0.0, 0.1},  {0.2, 0.0, kPi},   {-0.3, -0.4, -2.9}};
  return s;
}

const std::vector<Pose>& poses() {
  static const std::vector<Pose> p = {{0, 0, 0}, {1.5, -2.0, 0.7}, {-3.0, 4.0, -2.8}, {0, 0, 9.0}};
  return p;
}

TEST(OdometryModel, PredictIsComposeAndTheDecompositionIsExact) {
  const OdometryModel model(kDistinct);
  for (const Pose& x : poses())
    for (const OdometryDelta& u : steps()) {
      const Pose f = model.predict(x, u);
      EXPECT_EQ(f, compose(x, u));
      // The three motions rebuild the step: the noiseless sampler lands on x ⊕ u, heading
      // continued (not wrapped).
      const Pose g = compose_motion(x, decompose_odometry(u));
      EXPECT_NEAR((g - f).norm(), 0.0, 1e-12) << "x " << x.transpose() << ", u " << u.transpose();
      const OdometryMotion m = decompose_odometry(u);
      EXPECT_GE(m.trans, 0.0);
      EXPECT_LE(std::abs(m.rot1), kPi);
    }
}

TEST(OdometryModel, DecompositionOfSimpleSteps) {
  OdometryMotion m = decompose_odometry({1.0, 1.0, 0.5});
  EXPECT_DOUBLE_EQ(m.rot1, kPi / 4);
  EXPECT_DOUBLE_EQ(m.trans, std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(m.rot2, 0.5 - kPi / 4);
  m = decompose_odometry({0.0, 0.0, 0.7});  // no travel: no direction, the turn is rot2
  EXPECT_EQ(m.rot1, 0.0);
  EXPECT_EQ(m.trans, 0.0);
  EXPECT_EQ(m.rot2, 0.7);
  m = decompose_odometry({-2.0, 0.0, 0.0});  // backing up: the exact motion turns round twice
  EXPECT_DOUBLE_EQ(m.rot1, kPi);
  EXPECT_DOUBLE_EQ(m.rot2, -kPi);
}

TEST(OdometryModel, VariancesOfAPureTranslationAndAPureRotation) {
  const double d = 0.8, phi = 0.6;
  const Vec<3> forward = odometry_variances({d, 0.0, 0.0}, kDistinct);
  EXPECT_DOUBLE_EQ(forward(0), 0.2 * d * d);  // alpha2 trans^2
  EXPECT_DOUBLE_EQ(forward(1), 0.3 * d * d);  // alpha3 trans^2
  EXPECT_DOUBLE_EQ(forward(2), 0.2 * d * d);
  const Vec<3> turn = odometry_variances({0.0, 0.0, phi}, kDistinct);
  EXPECT_DOUBLE_EQ(turn(0), 0.0);
  EXPECT_DOUBLE_EQ(turn(1), 0.4 * phi * phi);  // alpha4 rot2^2
  EXPECT_DOUBLE_EQ(turn(2), 0.1 * phi * phi);  // alpha1 rot2^2
  // A general step: rot1 = pi/4, trans = sqrt(2), rot2 = 0.5 - pi/4.
  const double r1 = kPi / 4, r2 = 0.5 - kPi / 4, t2 = 2.0;
  const Vec<3> general = odometry_variances({1.0, 1.0, 0.5}, kDistinct);
  EXPECT_NEAR(general(0), 0.1 * r1 * r1 + 0.2 * t2, 1e-15);
  EXPECT_NEAR(general(1), 0.3 * t2 + 0.4 * (r1 * r1 + r2 * r2), 1e-15);
  EXPECT_NEAR(general(2), 0.1 * r2 * r2 + 0.2 * t2, 1e-15);
}

TEST(OdometryModel, BackingUpIsAsNoisyAsDrivingForward) {
  const Vec<3> forward = odometry_variances({0.8, 0.0, 0.0}, kDistinct);
  const Vec<3> backward = odometry_variances({-0.8, 0.0, 0.0}, kDistinct);
  EXPECT_NEAR((backward - forward).norm(), 0.0, 1e-15);
  // Backing up while turning by 0.3: the turn counts, the half turns of the decomposition do not.
  const Vec<3> back_turn = odometry_variances({-0.8, 0.0, 0.3}, kDistinct);
  const Vec<3> fwd_turn = odometry_variances({0.8, 0.0, 0.3}, kDistinct);
  EXPECT_NEAR((back_turn - fwd_turn).norm(), 0.0, 1e-15);
  EXPECT_NEAR(back_turn(2), 0.1 * 0.09 + 0.2 * 0.64, 1e-15);
  // A half turn on the spot is a half turn (nav2's per-rotation folding would make it noiseless).
  const Vec<3> half_turn = odometry_variances({0.0, 0.0, kPi}, kDistinct);
  EXPECT_NEAR(half_turn(2), 0.1 * kPi * kPi, 1e-14);
  EXPECT_NEAR(half_turn(1), 0.4 * kPi * kPi, 1e-14);
}

TEST(OdometryModel, ShortStepsAreTurnsOnTheSpotForTheNoise) {
  // 1 mm sideways: atan2 says a quarter turn, the noise must not.
  const double t = 1e-3;
  const Vec<3> v = odometry_variances({0.0, t, 0.0}, kDistinct);
  EXPECT_NEAR(v(0), 0.2 * t * t, 1e-18);
  EXPECT_NEAR(v(1), 0.3 * t * t, 1e-18);
  EXPECT_NEAR(v(2), 0.2 * t * t, 1e-18);
  // The same sideways step above the threshold counts the quarter turns.
  const Vec<3> w = odometry_variances({0.0, 0.02, 0.0}, kDistinct);
  EXPECT_NEAR(w(0), 0.1 * kPi * kPi / 4 + 0.2 * 4e-4, 1e-15);
}

TEST(OdometryModel, JacobianMatchesFiniteDifferences) {
  const OdometryModel model(kDistinct);
  const double h = 1e-6;
  for (const Pose& x : poses())
    for (const OdometryDelta& u : steps()) {
      const Mat3 j = model.motion_jacobian(x, u);
      const OdometryMotion m = decompose_odometry(u);
      for (int k = 0; k < 3; ++k) {
        OdometryMotion plus = m, minus = m;
        double* p[3] = {&plus.rot1, &plus.trans, &plus.rot2};
        double* q[3] = {&minus.rot1, &minus.trans, &minus.rot2};
        *p[k] += h;
        *q[k] -= h;
        const Vec<3> fd = (compose_motion(x, plus) - compose_motion(x, minus)) / (2 * h);
        EXPECT_NEAR((fd - j.col(k)).norm(), 0.0, 1e-8)
            << "column " << k << ", x " << x.transpose() << ", u " << u.transpose();
      }
    }
}

TEST(OdometryModel, CovarianceIsTheLinearisedFormAndAlwaysSpd) {
  const Vec<3> floor(0.01, 0.02, 0.003);
  const OdometryModel model(kDistinct, floor);
  for (const Pose& x : poses())
    for (const OdometryDelta& u : steps()) {
      const Mat3 j = model.motion_jacobian(x, u);
      const Mat3 expected = j * odometry_variances(u, kDistinct).asDiagonal() * j.transpose() +
                            Mat3(floor.cwiseAbs2().asDiagonal());
      const Mat3 sigma = model.process_covariance(x, u);
      EXPECT_NEAR((sigma - expected).norm(), 0.0, 1e-14);
      EXPECT_NEAR((sigma - sigma.transpose()).norm(), 0.0, 1e-15);
      EXPECT_EQ(Eigen::LLT<Mat3>(sigma).info(), Eigen::Success);
      Pose f;
      Mat3 s;
      model.predict_with_covariance(x, u, f, s);
      EXPECT_EQ(f, model.predict(x, u));
      EXPECT_EQ(s, sigma);
    }
  // Standing still: every variance is 0, only the floor remains.
  const Mat3 still = model.process_covariance(Pose(1, 2, 3), OdometryDelta::Zero());
  EXPECT_EQ(still, Mat3(floor.cwiseAbs2().asDiagonal()));
}

// Small noise (sd of a few hundredths): the linearisation error of the covariance is of relative
// order sd^2 ~ 1e-3 of its entries, far below the sampling error allowed here.
TEST(OdometryModel, GaussianFormMatchesTheSamplerForSmallNoise) {
  const OdometryAlphas small{.alpha1 = 2e-3, .alpha2 = 1e-3, .alpha3 = 3e-3, .alpha4 = 1.5e-3};
  const OdometryModel model(small);
  const std::vector<std::pair<Pose, OdometryDelta>> cases = {{{1.5, -2.0, 0.7}, {0.4, 0.15, 0.35}},
                                                             {{-3.0, 4.0, -2.8}, {-0.6, 0.1, -0.2}},
                                                             {{0.0, 0.0, 1.0}, {0.05, 0.3, -0.9}}};
  constexpr int kDraws = 40000;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const auto& [x, u] = cases[c];
    Rng rng({.seed = 11, .step = c, .purpose = purpose::kProcessNoise});
    std::vector<Vec<3>> draws(kDraws);
    Vec<3> mean = Vec<3>::Zero();
    for (Vec<3>& d : draws) {
      d = model.sample(x, u, rng);
      mean += d / kDraws;
    }
    // The sampler has no floor: compare with J diag(var) J^T.
    const Mat3 sigma =
        model.process_covariance(x, u) - Mat3(model.floor_std().cwiseAbs2().asDiagonal());
    const Pose f = model.predict(x, u);
    for (int i = 0; i < 3; ++i) {
      const double se_mean = std::sqrt(sigma(i, i) / kDraws);
      EXPECT_NEAR(mean(i), f(i), 4.5 * se_mean) << "case " << c << ", mean " << i;
      for (int k = 0; k < 3; ++k) {
        // Sample covariance and its standard error from the products' own spread.
        double s1 = 0, s2 = 0;
        for (const Vec<3>& d : draws) {
          const double p = (d(i) - mean(i)) * (d(k) - mean(k));
          s1 += p;
          s2 += p * p;
        }
        const double cov = s1 / (kDraws - 1);
        const double var_p = (s2 / kDraws - (s1 / kDraws) * (s1 / kDraws));
        const double se = std::sqrt(var_p / kDraws);
        EXPECT_NEAR(cov, sigma(i, k), 4.5 * se) << "case " << c << ", entry " << i << k;
      }
    }
  }
}

TEST(OdometryModel, PerturbedOdometryIsTheSamplerFromTheOrigin) {
  for (const Pose& x : poses())
    for (std::size_t k = 0; k < steps().size(); ++k) {
      const OdometryDelta& u = steps()[k];
      const StreamKey key{.seed = 5, .step = k, .purpose = purpose::kData};
      Rng a(key), b(key), c(key);
      const OdometryDelta reported = perturb_odometry(u, kDistinct, a);
      EXPECT_EQ(reported, sample_odometry(Pose::Zero(), u, kDistinct, b));
      // Dead reckoning with the reported increment is a draw of the sampler from x.
      const Pose via_odometry = compose(x, reported);
      const Pose sampled = OdometryModel(kDistinct).sample(x, u, c);
      EXPECT_NEAR((via_odometry - sampled).norm(), 0.0, 1e-12) << "u " << u.transpose();
    }
  // Without noise the reported increment is the true one.
  Rng rng({.seed = 1});
  const OdometryDelta u(0.3, -0.2, 0.4);
  EXPECT_NEAR((perturb_odometry(u, {0, 0, 0, 0}, rng) - u).norm(), 0.0, 1e-15);
}

std::string construction_error(const OdometryAlphas& a, const Vec<3>& floor = {0.1, 0.1, 0.1}) {
  try {
    OdometryModel model(a, floor);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(OdometryModel, BadAlphasAreRefusedByName) {
  const double nan = std::nan("");
  EXPECT_EQ(construction_error({.alpha1 = -0.1}),
            "odometry alpha1 (rotation noise from rotation): expected a finite value >= 0, got "
            "-0.1");
  EXPECT_EQ(construction_error({.alpha2 = nan}),
            "odometry alpha2 (rotation noise from translation): expected a finite value >= 0, got "
            "nan");
  EXPECT_EQ(construction_error({.alpha3 = std::numeric_limits<double>::infinity()}),
            "odometry alpha3 (translation noise from translation): expected a finite value >= 0, "
            "got inf");
  EXPECT_EQ(construction_error({.alpha4 = -1}),
            "odometry alpha4 (translation noise from rotation): expected a finite value >= 0, "
            "got -1");
  EXPECT_EQ(construction_error({.alpha1 = 0, .alpha2 = 0, .alpha3 = 0, .alpha4 = 0}), "no error");
  EXPECT_EQ(construction_error({}, {0.1, 0.0, 0.1}),
            "odometry floor_std: expected finite positive std devs (x [m], y [m], heading [rad]), "
            "got (0.1, 0, 0.1)");
  EXPECT_NE(construction_error({}, {0.1, nan, 0.1}), "no error");
  Rng rng({.seed = 1});
  EXPECT_THROW(perturb_odometry({1, 0, 0}, {.alpha3 = nan}, rng), InvalidArgument);
}

}  // namespace
}  // namespace implicit::robot
