// Implicit and standard MCL: spec §3.7 oracles (Case A, B), the linear-sensor identity of §3.4,
// periodicity in the heading, agreement of the two proposals, a synthetic run, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include <Eigen/LU>

#include "implicit/core/jet.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/filter/particle_filter.hpp"

namespace implicit::filter {
namespace {

using robot::LandmarkMap;
using robot::RangeBearingSensor;
using robot::UteModel;

// Spec §3.1 oracle state: X_{n-1} = (10, 5, 0.3), encoder speed 3, steering 0.1.
const Pose kPrevious(10.0, 5.0, 0.3);
Control oracle_control() {
  const UteModel m;
  return Control(m.axle_speed(3.0, 0.1), 0.1);
}

// Relative comparison |a - b| <= tol * max(1, |b|), entrywise.
template <typename A, typename B>
void expect_rel(const A& a, const B& b, double tol, const char* what) {
  for (Eigen::Index i = 0; i < b.size(); ++i)
    EXPECT_NEAR(a(i), b(i), tol * std::max(1.0, std::abs(b(i)))) << what << " entry " << i;
}

// One step of the landmark observation model as the filter hands it to a proposal: the model
// (map indices as ids), the detections and the context. Not copyable: the context points into it.
template <typename Motion, typename Sensor>
struct LandmarkStep {
  robot::LandmarkObservation<Sensor> model;
  robot::LandmarkDetections<Sensor> detections;
  ObservationContext<Motion, robot::LandmarkObservation<Sensor>> ctx;

  LandmarkStep(const Motion& motion, const Sensor& sensor, const std::vector<Landmark>& map,
               std::span<const LabelledMeasurement> z, const Control& u,
               AssociationOptions association = {})
      : model(sensor, landmark_map(map), association), detections(model.view(z)) {
    ctx.motion = &motion;
    ctx.observation = &model;
    ctx.u = u;
    ctx.z = &detections;
  }
  LandmarkStep(const LandmarkStep&) = delete;
  LandmarkStep& operator=(const LandmarkStep&) = delete;

  static LandmarkMap landmark_map(const std::vector<Landmark>& map) {
    LandmarkMap m;
    for (std::size_t i = 0; i < map.size(); ++i) m.add(static_cast<int>(i), map[i]);
    return m;
  }
};

// F^j of spec §3.3 WITHOUT constants, for the §3.7 tables.
MclObjective<RangeBearingSensor> oracle_objective(const std::vector<Landmark>& m,
                                                  const std::vector<Measurement>& z,
                                                  const RangeBearingSensor& sensor) {
  const UteModel model;
  const Control u = oracle_control();
  const Mat3 sigma1 = model.process_covariance(kPrevious, u);
  MclObjective<RangeBearingSensor> f;
  f.reset(sensor, sensor.noise_covariance().llt().solve(Mat2::Identity()),
          model.predict(kPrevious, u), sigma1.llt().solve(Mat3::Identity()), 0.0);
  for (std::size_t i = 0; i < m.size(); ++i) f.add(m[i], z[i]);
  return f;
}

TEST(MclOracle, CaseA) {
  const RangeBearingSensor sensor;
  const auto f =
      oracle_objective({Landmark(20, 12)}, {Measurement(12.1682955572, 1.8806599794)}, sensor);
  const Pose fj = f.prediction();
  expect_rel(fj, Vec<3>(10.0692764169, 5.0322421519, 0.3027326781), 1e-9, "f");
  Vec<3> g;
  Mat3 h;
  EXPECT_NEAR(f.evaluate(fj, &g, &h), 0.014014336680, 1e-8 * 0.014);
  // At x = f only the measurement term contributes, and z is given to 1e-10: through the bearing
  // information 1/sigma2 = 1146 that rounding moves the gradient by up to ~1e-7.
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(g(i), Vec<3>(0.5634353514, 0.4845133583, 0.8856871421)(i), 2e-7) << "grad at f";
  Mat3 h_ref;
  h_ref << 504.2632900481, -1075.0720121249, 4463.5484653852, -1075.0720121249, 3660.1271445824,
      -14283.2532646218, 4463.5484653852, -14283.2532646218, 58216.5213328328;
  expect_rel(h.reshaped(), h_ref.reshaped(), 1e-8, "hessian at f");

  const Pose x2 = fj + Vec<3>(0.2, -0.1, 0.01);
  EXPECT_NEAR(f.evaluate(x2, &g, &h), 76.093242330183, 1e-8 * 76.1);
  expect_rel(g, Vec<3>(253.5311514905, -723.3752344939, 2903.9233431589), 1e-8, "grad at x2");
  h_ref << 504.1078441596, -1075.0042387521, 4461.8076973143, -1075.0042387521, 3660.244117105,
      -14283.4859080862, 4461.8076973143, -14283.4859080862, 58216.5213328328;
  expect_rel(h.reshaped(), h_ref.reshaped(), 1e-8, "hessian at x2");

  const PoseMinimum r = newton_minimize<SmallFactor<3>>(f, fj, mcl_newton_options());
  ASSERT_TRUE(usable(r) && r.converged());
  EXPECT_TRUE(r.exact_factor);
  expect_rel(r.x, Vec<3>(10.0667353158, 5.028063506, 0.3018870747), 1e-9, "mu");
  EXPECT_NEAR(r.value, 0.011911716008, 1e-8 * 0.0119);
  EXPECT_NEAR(r.factor.log_det_L(), 10.545986532115, 1e-8 * 10.5);
  Mat3 l_ref;
  l_ref << 22.4559423206, 0, 0, -47.874846178, 36.9881312124, 0, 198.7694811942, -128.8854582146,
      45.7793986354;
  expect_rel(r.factor.matrixL().reshaped(), l_ref.reshaped(), 1e-8, "L");
  EXPECT_LE(r.evaluations, 8);  // spec §3.9: 4-5 Newton iterations
}

TEST(MclOracle, CaseBDerivativesAndMinimiser) {
  const RangeBearingSensor sensor;
  const std::vector<Landmark> m{Landmark(20, 12), Landmark(11, 17)};
  const std::vector<Measurement> z{Measurement(12.3, 1.85), Measurement(12.1, 2.74)};
  const auto f = oracle_objective(m, z, sensor);
  expect_rel(sensor.predict(f.prediction(), m[1]), Vec<2>(12.0038941306, 2.7612469407), 1e-9,
             "h(f, m2)");
  const Pose xt(10.1692764169, 4.9822421519, 0.3227326781);
  Vec<3> g;
  Mat3 h;
  EXPECT_NEAR(f.evaluate(xt, &g, &h), 47.977334867179, 1e-8 * 48);
  expect_rel(g, Vec<3>(198.8364716097, -575.5285795415, 2279.2775630361), 1e-8, "grad");
  Mat3 h_ref;
  h_ref << 512.1047008408, -1074.0587112778, 4367.7824848394, -1074.0587112778, 3679.8557908281,
      -14276.8021410386, 4367.7824848394, -14276.8021410386, 59362.4369230944;
  expect_rel(h.reshaped(), h_ref.reshaped(), 1e-8, "hessian");

  // Landmark 1's measurement term alone: F minus the prior part.
  MclObjective<RangeBearingSensor> one;
  one.reset(sensor, sensor.noise_covariance().llt().solve(Mat2::Identity()), f.prediction(),
            Mat3::Zero(), 0.0);
  one.add(m[0], z[0]);
  EXPECT_NEAR(one.evaluate(xt, &g, &h), 0.676554801942, 1e-8);
  expect_rel(g, Vec<3>(4.5981855796, 1.1806789037, -20.6620249962), 1e-8, "term grad");
  h_ref << 15.9102249789, 5.8707270382, -55.1212903694, 5.8707270382, 11.5776838541, 77.215854536,
      -55.1212903694, 77.215854536, 1145.9155902616;
  expect_rel(h.reshaped(), h_ref.reshaped(), 1e-8, "term hessian");

  const PoseMinimum r = newton_minimize<SmallFactor<3>>(f, f.prediction(), mcl_newton_options());
  ASSERT_TRUE(usable(r) && r.converged());
  expect_rel(r.x, Vec<3>(10.0180469054, 5.0788693051, 0.3187026551), 1e-9, "mu");
  EXPECT_NEAR(r.value, 0.543789188458, 1e-8);
  EXPECT_NEAR(r.factor.log_det_L(), 10.869741220601, 1e-8 * 10.9);
}

TEST(MclOracle, HessianMatchesAutodiff) {
  // The analytic gradient and Hessian of F^j against second-order forward autodiff (Jet2).
  const RangeBearingSensor sensor;
  const std::vector<Landmark> m{Landmark(20, 12), Landmark(11, 17), Landmark(3, -4)};
  const std::vector<Measurement> z{Measurement(12.3, 1.85), Measurement(12.1, 2.74),
                                   Measurement(9.0, -0.9)};
  const auto f = oracle_objective(m, z, sensor);
  const UteModel model;
  const Mat3 info =
      model.process_covariance(kPrevious, oracle_control()).llt().solve(Mat3::Identity());
  const Mat2 ninfo = sensor.noise_covariance().llt().solve(Mat2::Identity());
  const Pose fj = f.prediction();
  auto functor = [&](const auto& x) {
    using J = std::decay_t<decltype(x(0))>;
    J d0 = x(0) - fj(0), d1 = x(1) - fj(1), d2 = x(2) - fj(2);
    const J dv[3] = {d0, d1, d2};
    J v = J(0.0) * x(0);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) v = v + 0.5 * info(a, b) * dv[a] * dv[b];
    for (std::size_t i = 0; i < m.size(); ++i) {
      using std::atan2, std::sqrt, std::floor;
      const J dx = m[i](0) - x(0), dy = m[i](1) - x(1);
      const J er = sqrt(dx * dx + dy * dy) - z[i](0);
      J eb = atan2(dy, dx) - x(2) + kPi / 2 - z[i](1);
      eb = eb - 2 * kPi * floor((eb + kPi) / (2 * kPi));
      v = v + 0.5 * (ninfo(0, 0) * er * er + 2 * ninfo(0, 1) * er * eb + ninfo(1, 1) * eb * eb);
    }
    return v;
  };
  for (const Vec<3>& dx : {Vec<3>(0, 0, 0), Vec<3>(0.3, -0.2, 0.05), Vec<3>(-1.0, 0.5, -0.3)}) {
    const Pose x = fj + dx;
    auto [v, g_ad, h_ad] = autodiff_hessian<3>(functor, x);
    Vec<3> g;
    Mat3 h;
    EXPECT_NEAR(f.evaluate(x, &g, &h), v, 1e-10 * std::max(1.0, std::abs(v)));
    expect_rel(g, g_ad, 1e-10, "grad vs autodiff");
    expect_rel(h.reshaped(), h_ad.reshaped(), 1e-10, "hessian vs autodiff");
  }
}

TEST(MclOracle, FastPathMatchesGenericPath) {
  // The written-out range-bearing evaluation against the sensor-interface one, with a
  // non-diagonal noise information (exercises n01). Tolerance 1e-12 relative: the two differ
  // only in the order of floating-point operations on O(1e4) terms.
  const RangeBearingSensor sensor;
  const UteModel model;
  const Control u = oracle_control();
  Mat2 ninfo;
  ninfo << 20.0, 3.0, 3.0, 1100.0;
  MclObjective<RangeBearingSensor> f;
  f.reset(sensor, ninfo, model.predict(kPrevious, u),
          model.process_covariance(kPrevious, u).llt().solve(Mat3::Identity()), 1.25);
  f.add(Landmark(20, 12), Measurement(12.3, 1.85));
  f.add(Landmark(11, 17), Measurement(12.1, 2.74));
  f.add(Landmark(3, -4), Measurement(9.0, -0.9));
  for (const Vec<3>& dx : {Vec<3>(0, 0, 0), Vec<3>(0.3, -0.2, 0.05), Vec<3>(-1.0, 0.5, 3.0)}) {
    const Pose x = f.prediction() + dx;
    Vec<3> g0, g1;
    Mat3 h0, h1, gn0, gn1;
    const double v0 = f.evaluate(x, &g0, &h0, &gn0);
    const double v1 = f.evaluate_generic(x, &g1, &h1, &gn1);
    EXPECT_NEAR(v0, v1, 1e-12 * std::max(1.0, std::abs(v1)));
    EXPECT_NEAR(f.evaluate(x), v1, 1e-12 * std::max(1.0, std::abs(v1)));
    const double scale = std::max(1.0, h1.cwiseAbs().maxCoeff());
    expect_rel(g0, g1, 1e-12 * scale, "gradient");
    EXPECT_LE((h0 - h1).cwiseAbs().maxCoeff(), 1e-12 * scale) << "hessian";
    EXPECT_LE((gn0 - gn1).cwiseAbs().maxCoeff(), 1e-12 * scale) << "gauss-newton";
  }
}

TEST(MclOracle, FusedModelAndSensorCallsMatchSeparateOnes) {
  const UteModel model;
  const RangeBearingSensor sensor;
  const Control u = oracle_control();
  for (const Pose& x : {kPrevious, Pose(-3.0, 40.0, -2.5), Pose(100.0, -7.0, 9.0)}) {
    Pose f;
    Mat3 s;
    model.predict_with_covariance(x, u, f, s);
    expect_rel(f, model.predict(x, u), 1e-14, "mean");
    expect_rel(s.reshaped(), model.process_covariance(x, u).reshaped(), 1e-14, "covariance");
    const Landmark m(20, 12);
    Measurement h;
    robot::Mat23 j;
    sensor.predict_with_jacobian(x, m, h, j);
    expect_rel(h, sensor.predict(x, m), 1e-14, "prediction");
    expect_rel(j.reshaped(), sensor.jacobian_pose(x, m).reshaped(), 1e-14, "jacobian");
  }
}

// The Ute and the range-bearing sensor seen only through the MotionModel / LandmarkSensor
// interfaces (no fused calls), as a user's own robot would be.
struct PlainUte {
  UteModel model;
  double dt() const { return model.dt(); }
  Pose predict(const Pose& x, const Control& u) const { return model.predict(x, u); }
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    return model.process_covariance(x, u);
  }
};
struct PlainRangeBearing {
  RangeBearingSensor sensor;
  Measurement predict(const Pose& x, const Landmark& m) const { return sensor.predict(x, m); }
  static Measurement residual(const Measurement& a, const Measurement& b) {
    return RangeBearingSensor::residual(a, b);
  }
  robot::Mat23 jacobian_pose(const Pose& x, const Landmark& m) const {
    return sensor.jacobian_pose(x, m);
  }
  void hessian_pose(const Pose& x, const Landmark& m, Mat3& h0, Mat3& h1) const {
    sensor.hessian_pose(x, m, h0, h1);
  }
  const Mat2& noise_covariance() const { return sensor.noise_covariance(); }
};
static_assert(!robot::MotionModelWithCovariance<PlainUte>);
static_assert(!robot::LandmarkSensorWithFusedJacobian<PlainRangeBearing>);

TEST(ImplicitProposal, FastPathsGiveTheSameUpdateAsTheInterfaces) {
  // Same particles, same streams: the fused model/sensor calls and the written-out objective
  // change only the order of floating-point operations, so samples and log weights agree to
  // round-off (1e-9 relative: Newton amplifies 1e-16 differences by the condition of H ~ 1e5).
  const UteModel model;
  const RangeBearingSensor sensor;
  const std::vector<Landmark> map{Landmark(20, 12), Landmark(11, 17), Landmark(3, -4),
                                  Landmark(14, 9)};
  const Control u = oracle_control();
  const Pose truth = model.predict(kPrevious, u);
  std::vector<LabelledMeasurement> z;
  for (int k : {0, 1, 3}) z.push_back({sensor.predict(truth, map[k]) + Vec<2>(0.05, -0.01), -1});
  const PlainUte plain_model{model};
  const PlainRangeBearing plain_sensor{sensor};
  const LandmarkStep fast_step(model, sensor, map, z, u);
  const LandmarkStep slow_step(plain_model, plain_sensor, map, z, u);
  const auto& fast = fast_step.ctx;
  const auto& slow = slow_step.ctx;
  const ImplicitProposal implicit;
  const BootstrapProposal bootstrap;
  for (std::uint64_t j = 0; j < 50; ++j) {
    const Pose previous = kPrevious + Vec<3>(0.05 * std::sin(j), 0.05 * std::cos(j), 0.0);
    for (int which = 0; which < 2; ++which) {
      Rng r1({3, 1, j, purpose::kReference}), r2({3, 1, j, purpose::kReference});
      ParticleStats s1, s2;
      Pose x1, x2;
      const double w1 = which == 0 ? implicit.propose(fast, previous, r1, x1, s1)
                                   : bootstrap.propose(fast, previous, r1, x1, s1);
      const double w2 = which == 0 ? implicit.propose(slow, previous, r2, x2, s2)
                                   : bootstrap.propose(slow, previous, r2, x2, s2);
      ASSERT_TRUE(std::isfinite(w1)) << j;
      EXPECT_NEAR(w1, w2, 1e-9 * std::max(1.0, std::abs(w2))) << "particle " << j;
      expect_rel(x1, x2, 1e-9, "sample");
      // Implicit associates at f^j with the predictive covariance: all three match there.
      if (which == 0) {
        EXPECT_EQ(s1.used, 3);
      }
      EXPECT_EQ(s1.used, s2.used);
      EXPECT_EQ(s1.dropped, s2.dropped);
    }
  }
}

TEST(SmallFactor3, MatchesEigenAndRejectsNonSpd) {
  Mat3 a;
  a << 4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0;
  SmallFactor<3> c;
  ASSERT_TRUE(c.compute(a));
  const Eigen::LLT<Mat3> ref(a);
  EXPECT_LE((c.matrixL() - Mat3(ref.matrixL())).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(c.log_det_L(), 0.5 * std::log(a.determinant()), 1e-14);
  const Vec<3> b(1.0, -2.0, 0.5);
  expect_rel(c.solve(b), ref.solve(b), 1e-14, "solve");
  EXPECT_LE((c.inverse() * a - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  expect_rel(c.solve_upper(b), Vec<3>(ref.matrixU().solve(b)), 1e-14, "upper solve");
  Mat3 indefinite = a;
  indefinite(2, 2) = -1.0;
  EXPECT_FALSE(c.compute(indefinite));
  Mat3 nan = a;
  nan(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(c.compute(nan));
  EXPECT_FALSE(c.compute(Mat3::Zero()));
}

TEST(MclOracle, PeriodicInHeading) {
  // Shifting the previous heading and the state heading by 2 pi leaves F unchanged (residuals
  // are wrapped, the state heading is not). Tolerance 1e-12 relative: round-off of sin/cos at
  // angles near 6.6 and of Sigma1^-1 (entries ~5e4) times heading differences.
  const RangeBearingSensor sensor;
  const UteModel model;
  const Control u = oracle_control();
  auto build = [&](const Pose& prev) {
    MclObjective<RangeBearingSensor> f;
    f.reset(sensor, sensor.noise_covariance().llt().solve(Mat2::Identity()), model.predict(prev, u),
            model.process_covariance(prev, u).llt().solve(Mat3::Identity()), 0.0);
    f.add(Landmark(20, 12), Measurement(12.3, 1.85));
    f.add(Landmark(11, 17), Measurement(12.1, 2.74));
    return f;
  };
  const Pose shift(0, 0, 2 * kPi);
  const auto f0 = build(kPrevious);
  const auto f1 = build(kPrevious + shift);
  for (const Vec<3>& dx : {Vec<3>(0, 0, 0), Vec<3>(0.1, -0.05, 0.02), Vec<3>(0.2, 0.3, -3.0)}) {
    const Pose x = f0.prediction() + dx;
    const double a = f0.evaluate(x), b = f1.evaluate(x + shift);
    EXPECT_NEAR(a, b, 1e-12 * std::max(1.0, std::abs(a)));
    // The measurement part alone is periodic in the state heading for a fixed prior.
    MclObjective<RangeBearingSensor> meas;
    meas.reset(sensor, sensor.noise_covariance().llt().solve(Mat2::Identity()), x, Mat3::Zero(),
               0.0);
    meas.add(Landmark(20, 12), Measurement(12.3, 1.85));
    EXPECT_NEAR(meas.evaluate(x), meas.evaluate(x + shift),
                1e-12 * std::max(1.0, meas.evaluate(x)));
  }
}

// One update of the proposal from a fixed previous pose: increments and samples for M streams.
// `gate`: the association's chi-square gate (also sets the clutter density p0).
template <typename Proposal, typename Sensor>
void one_step(const Proposal& p, const Sensor& sensor, const std::vector<Landmark>& map,
              const std::vector<LabelledMeasurement>& z, std::size_t m, std::vector<double>& log_w,
              std::vector<Pose>& x, double gate = robot::kChiSquare2Dof99) {
  const UteModel model;
  AssociationOptions association;
  association.gate = gate;
  const LandmarkStep step(model, sensor, map, z, oracle_control(), association);
  log_w.resize(m);
  x.resize(m);
  for (std::size_t j = 0; j < m; ++j) {
    Rng rng({11, 1, j, Proposal::kPurpose});
    ParticleStats st;
    log_w[j] = p.propose(step.ctx, kPrevious, rng, x[j], st);
  }
}

// A linear sensor h(x) = C x + c (the landmark is ignored): F is exactly quadratic.
struct LinearSensor {
  Eigen::Matrix<double, 2, 3> c;
  Vec<2> offset;
  Mat2 noise;
  Measurement predict(const Pose& x, const Landmark&) const { return c * x + offset; }
  static Measurement residual(const Measurement& a, const Measurement& b) { return a - b; }
  robot::Mat23 jacobian_pose(const Pose&, const Landmark&) const { return c; }
  const Mat2& noise_covariance() const { return noise; }
};
static_assert(robot::LandmarkSensor<LinearSensor>);

TEST(ImplicitProposal, LinearSensorWeightIsExactPredictiveLikelihood) {
  // Spec §3.4: with h linear, every implicit weight equals N(z; C f + c, C Sigma1 C^T + Sigma2).
  LinearSensor s;
  s.c << 1.0, 0.2, -0.5, 0.3, -1.0, 2.0;
  s.offset = Vec<2>(0.5, -1.0);
  s.noise << 0.05, 0.01, 0.01, 0.02;
  const UteModel model;
  const Control u = oracle_control();
  const Pose f = model.predict(kPrevious, u);
  const Mat3 sigma1 = model.process_covariance(kPrevious, u);
  const std::vector<Landmark> map{Landmark(0, 0)};
  const Measurement z = s.c * f + s.offset + Vec<2>(0.3, -0.2);
  const std::vector<LabelledMeasurement> obs{{z, 0}, {z + Vec<2>(0.1, 0.05), 0}};
  // Exact: stacked 4-D Gaussian N([z1; z2]; [Cf+c; Cf+c], [[CSC^T+R, CSC^T],[CSC^T, CSC^T+R]]).
  const Mat2 csc = s.c * sigma1 * s.c.transpose();
  Eigen::Matrix4d cov;
  cov << csc + s.noise, csc, csc, csc + s.noise;
  Eigen::Vector4d r;
  r << obs[0].z - (s.c * f + s.offset), obs[1].z - (s.c * f + s.offset);
  const Eigen::LLT<Eigen::Matrix4d> llt(cov);
  const double exact = -2.0 * kLog2Pi - std::log(Eigen::Matrix4d(llt.matrixL()).diagonal().prod()) -
                       0.5 * r.dot(llt.solve(r));
  std::vector<double> lw;
  std::vector<Pose> x;
  one_step(ImplicitProposal{}, s, map, obs, 50, lw, x);
  for (double l : lw) EXPECT_NEAR(l, exact, 1e-10 * (1.0 + std::abs(exact)));
}

TEST(ImplicitProposal, CaseBPredictiveLikelihood) {
  // Spec §3.7 Case B: log p(z1, z2 | X_{n-1}) = 4.05513; implicit with M = 2e4 has relative SE
  // 8e-6, so 1e-3 is > 100 SE: a failure means a wrong constant, not bad luck.
  const RangeBearingSensor sensor;
  const std::vector<Landmark> map{Landmark(20, 12), Landmark(11, 17)};
  const std::vector<LabelledMeasurement> z{{Measurement(12.3, 1.85), 0},
                                           {Measurement(12.1, 2.74), 1}};
  std::vector<double> lw;
  std::vector<Pose> x;
  one_step(ImplicitProposal{}, sensor, map, z, 20000, lw, x);
  EXPECT_LT(std::abs(log_mean_exp(lw) - 4.05513), 1e-3);
  std::vector<double> w(lw.size());
  const auto s = normalize_log_weights(lw, w);
  EXPECT_GT(s.ess / 20000.0, 0.9999);

  ImplicitProposal random;
  random.map = ImplicitMap::kRandom;
  one_step(random, sensor, map, z, 20000, lw, x);
  EXPECT_LT(std::abs(log_mean_exp(lw) - 4.05513), 1e-3);
}

TEST(ImplicitProposal, BootstrapAgreesOnPredictiveLikelihoodAndPosteriorMean) {
  // Same Case B update with the bootstrap proposal: log mean w within 4.5 SE of 4.05513 (SE from
  // the weights, spec §1.5), and the posterior means of both proposals agree within 4.5 combined
  // SE (SE of a self-normalised mean: sqrt(sum wbar^2 (x - mean)^2)).
  const RangeBearingSensor sensor;
  const std::vector<Landmark> map{Landmark(20, 12), Landmark(11, 17)};
  const std::vector<LabelledMeasurement> z{{Measurement(12.3, 1.85), 0},
                                           {Measurement(12.1, 2.74), 1}};
  auto stats = [](const std::vector<double>& lw, const std::vector<Pose>& x, Vec<3>& mean,
                  Vec<3>& se) {
    std::vector<double> w(lw.size());
    normalize_log_weights(lw, w);
    mean.setZero();
    for (std::size_t j = 0; j < w.size(); ++j) mean += w[j] * x[j];
    Vec<3> v = Vec<3>::Zero();
    for (std::size_t j = 0; j < w.size(); ++j) v += (w[j] * w[j]) * (x[j] - mean).cwiseAbs2();
    se = v.cwiseSqrt();
  };
  std::vector<double> lwi, lwb;
  std::vector<Pose> xi, xb;
  one_step(ImplicitProposal{}, sensor, map, z, 20000, lwi, xi);
  one_step(BootstrapProposal{}, sensor, map, z, 400000, lwb, xb);
  EXPECT_LT(std::abs(log_mean_exp(lwb) - 4.05513), 4.5 * relative_standard_error(lwb));
  Vec<3> mi, sei, mb, seb;
  stats(lwi, xi, mi, sei);
  stats(lwb, xb, mb, seb);
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(std::abs(mi(k) - mb(k)), 4.5 * std::hypot(sei(k), seb(k))) << "component " << k;
  expect_rel(mi, Vec<3>(10.0180469054, 5.0788693051, 0.3187026551), 1e-3, "close to mu");
}

TEST(Association, GateAndClutterConstant) {
  // A detection far from every landmark is dropped and contributes log p0 (bootstrap) or -log p0
  // in F (implicit); p0 = N(gate boundary; 0, Sigma2).
  const RangeBearingSensor sensor;
  const double lp0 = robot::clutter_log_density(9.21, sensor.noise_covariance());
  const Mat2& s2 = sensor.noise_covariance();
  EXPECT_NEAR(lp0, -0.5 * 9.21 - kLog2Pi - 0.5 * std::log(s2.determinant()), 1e-12);
  const std::vector<Landmark> map{Landmark(20, 12)};
  const std::vector<LabelledMeasurement> far{{Measurement(3.0, 0.2), -1}};
  std::vector<double> lw;
  std::vector<Pose> x;
  one_step(BootstrapProposal{}, sensor, map, far, 10, lw, x, 9.21);
  for (double l : lw) EXPECT_DOUBLE_EQ(l, lp0);
  one_step(ImplicitProposal{}, sensor, map, far, 10, lw, x, 9.21);
  for (double l : lw) EXPECT_NEAR(l, lp0, 1e-9);  // F = prior + const: weight p0 exactly
  // ML picks the likelier of two candidates.
  const Pose pose(0, 0, kPi / 2);  // looking north: bearing pi/2 is straight ahead
  const std::vector<Landmark> two{Landmark(0, 10), Landmark(0, 12)};
  auto a = robot::associate_landmark(sensor, pose, Mat3::Zero(), std::span<const Landmark>(two), {},
                                     Measurement(11.8, kPi / 2), 9.21);
  EXPECT_EQ(a.index, 1);
  a = robot::associate_landmark(sensor, pose, Mat3::Zero(), std::span<const Landmark>(two), {},
                                Measurement(11.0, kPi / 2), 9.21);
  EXPECT_EQ(a.index, robot::Association::kNoMatch);  // d^2 = 1/0.05 = 20 > 9.21 for both
}

// ---- Filter runs on synthetic data --------------------------------------------------------

struct Synthetic {
  std::vector<Control> u;
  std::vector<Pose> truth;
  std::vector<std::vector<LabelledMeasurement>> z;
  LandmarkMap map;
};

// Truth sampled from the model itself (spec §3.6 "consistent" mode), with Sigma1 scaled down by
// `noise_scale` in P and Q; detections of landmarks within 20 m ahead every 8th step.
Synthetic make_synthetic(int steps, std::uint64_t seed, const UteModel& model) {
  Synthetic s;
  const RangeBearingSensor sensor;
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * kPi * k / 12.0;
    s.map.add(k, Landmark(15 * std::cos(a) + 3 * std::sin(3 * a), 15 * std::sin(a) + 10));
  }
  Pose x(0, 0, 0);
  const Mat2 l2 = sensor.noise_covariance().llt().matrixL();
  for (int n = 1; n <= steps; ++n) {
    const Control u(3.0, 0.12);
    Rng rng({seed, static_cast<std::uint64_t>(n), 0, purpose::kData});
    const Mat3 l1 = model.process_covariance(x, u).llt().matrixL();
    x = model.predict(x, u) + l1 * rng.normal_vector<3>();
    std::vector<LabelledMeasurement> z;
    if (n % 8 == 0)
      for (std::size_t k = 0; k < s.map.size(); ++k) {
        const Measurement h = sensor.predict(x, s.map.position(k));
        if (h(0) < 20 && wrap_angle(h(1)) > 0 && wrap_angle(h(1)) < kPi)
          z.push_back({h + l2 * rng.normal_vector<2>(), -1});
      }
    s.u.push_back(u);
    s.truth.push_back(x);
    s.z.push_back(z);
  }
  return s;
}

FilterOptions options(std::size_t m, std::uint64_t seed) {
  FilterOptions o;
  o.particles = m;
  o.seed = seed;
  return o;
}

template <typename Proposal>
std::vector<StepSummary> run(const Synthetic& s, const UteModel& model, Proposal p, std::size_t m,
                             std::uint64_t seed) {
  ParticleFilter pf(model, RangeBearingSensor(), s.map, p, options(m, seed));
  pf.initialize(Pose(0, 0, 0), Vec<3>(0.1, 0.1, 0.02).cwiseAbs2().asDiagonal().toDenseMatrix());
  std::vector<StepSummary> out;
  for (std::size_t n = 0; n < s.u.size(); ++n) out.push_back(pf.step(s.u[n], s.z[n]));
  return out;
}

robot::UteParams low_noise() {
  robot::UteParams p;
  p.control_std = Vec<2>(0.1, 0.1);  // spec §3.9 config B
  return p;
}

TEST(ParticleFilterRun, ImplicitTracksSyntheticTruthWithinPosteriorSpread) {
  // Truth drawn from the filter's own model: the position errors normalised by the filter's own
  // covariance, e^T P_xy^-1 e, have mean 2 for a consistent filter. Averaged over the 60 update
  // steps (correlated), a mean below 8 is a loose bound a lost filter fails by orders of
  // magnitude; also the RMSE must stay below 3 times the mean posterior std.
  const UteModel model(low_noise());
  const Synthetic s = make_synthetic(480, 5, model);
  const auto out = run(s, model, ImplicitProposal{}, 300, 3);
  double nees = 0.0, se = 0.0, tr = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (!out[k].updated) continue;
    const Vec<2> e = out[k].mean.head<2>() - s.truth[k].head<2>();
    const Mat2 p = out[k].covariance.topLeftCorner<2, 2>();
    nees += e.dot(p.llt().solve(e));
    se += e.squaredNorm();
    tr += p.trace();
    ++n;
    EXPECT_GT(out[k].log_likelihood_increment, -50.0) << "step " << k;
  }
  ASSERT_GE(n, 40);
  RecordProperty("mean_nees", std::to_string(nees / n));
  RecordProperty("rmse", std::to_string(std::sqrt(se / n)));
  EXPECT_LT(nees / n, 8.0);
  EXPECT_LT(std::sqrt(se / n), 3.0 * std::sqrt(tr / n));
  EXPECT_LT(std::sqrt(se / n), 0.5);
}

TEST(ParticleFilterRun, DeterministicAcrossThreadCounts) {
  const UteModel model;
  const Synthetic s = make_synthetic(120, 9, model);
  std::vector<StepSummary> a, b, c, d;
  {
    ThreadLimit limit(1);
    a = run(s, model, ImplicitProposal{}, 200, 4);
    c = run(s, model, BootstrapProposal{}, 200, 4);
  }
  {
    ThreadLimit limit(2);
    b = run(s, model, ImplicitProposal{}, 200, 4);
    d = run(s, model, BootstrapProposal{}, 200, 4);
  }
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].mean, b[k].mean) << k;
    EXPECT_EQ(a[k].log_likelihood_increment, b[k].log_likelihood_increment) << k;
    EXPECT_EQ(c[k].mean, d[k].mean) << k;
  }
  // Above 2048 particles the summary's trigonometry runs in parallel too.
  const Synthetic shorter = make_synthetic(40, 9, model);
  std::vector<StepSummary> e, f;
  {
    ThreadLimit limit(1);
    e = run(shorter, model, ImplicitProposal{}, 3000, 4);
  }
  {
    ThreadLimit limit(2);
    f = run(shorter, model, ImplicitProposal{}, 3000, 4);
  }
  for (std::size_t k = 0; k < e.size(); ++k) {
    EXPECT_EQ(e[k].mean, f[k].mean) << k;
    EXPECT_EQ(e[k].covariance, f[k].covariance) << k;
  }
}

TEST(ParticleFilterRun, RejectsBadInput) {
  const UteModel model;
  LandmarkMap map;
  map.add(1, Landmark(1, 1));
  EXPECT_THROW(ParticleFilter(model, RangeBearingSensor(), map, ImplicitProposal{}, options(0, 1)),
               InvalidArgument);
  ParticleFilter pf(model, RangeBearingSensor(), map, ImplicitProposal{}, options(4, 1));
  EXPECT_THROW(pf.initialize(Pose(0, 0, 0), -Mat3::Identity()), InvalidArgument);
  pf.initialize(Pose(0, 0, 0), Mat3::Identity());
  const std::vector<LabelledMeasurement> bad{{Measurement(1, std::nan("")), -1}};
  EXPECT_THROW(pf.step(Control(1, 0), bad), InvalidArgument);
  const std::vector<LabelledMeasurement> unknown{{Measurement(1, 1), 3}};
  EXPECT_THROW(pf.step(Control(1, 0), unknown), InvalidArgument);
}

// ---- GPS-aided reference track (alternative ground truth) --------------------------------

// The synthetic run as a LocalizationProblem with a GPS fix (truth + N(0, gps_std^2 I)) every 8th
// step (5 Hz at 40 Hz steps, as in the Car Park data).
LocalizationProblem synthetic_problem(const Synthetic& s, double gps_std, bool beacons,
                                      std::uint64_t seed) {
  LocalizationProblem p;
  p.map = s.map;
  p.initial_mean = Pose(0, 0, 0);
  p.initial_covariance = Vec<3>(0.1, 0.1, 0.02).cwiseAbs2().asDiagonal();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t n = 0; n < s.u.size(); ++n) {
    p.schedule.steps.push_back({0.025 * static_cast<double>(n + 1), s.u[n], -1});
    p.detections.push_back(beacons ? s.z[n] : std::vector<LabelledMeasurement>{});
    p.truth.position.push_back(s.truth[n].head<2>());
    p.truth.heading.push_back(s.truth[n](2));
    Vec<2> fix(nan, nan);
    if (n % 8 == 4) {
      Rng rng({seed, n, 0, purpose::kData});
      fix = s.truth[n].head<2>() + gps_std * rng.normal_vector<2>();
    }
    p.position_fixes.push_back(fix);
  }
  return p;
}

struct ReferenceErrors {
  double gps_rmse = 0.0;        ///< fixes vs truth, over the fix steps
  double reference_rmse = 0.0;  ///< reference track vs truth, over the same steps
  double unaided_rmse = 0.0;    ///< the same filter without the fixes, over the same steps
};

ReferenceErrors reference_errors(const UteModel& model, bool beacons, std::uint64_t seed) {
  const double gps_std = 0.5;
  const Synthetic s = make_synthetic(1200, seed, model);
  const LocalizationProblem p = synthetic_problem(s, gps_std, beacons, seed + 100);
  ReferenceOptions ro;
  ro.gps_std = gps_std;
  ro.particles = 400;
  const robot::TruthTrack ref =
      reference_track(p, model, RangeBearingSensor(), ImplicitProposal{}, ro);
  LocalizationProblem unaided = p;
  for (Vec<2>& f : unaided.position_fixes) f.setConstant(std::numeric_limits<double>::quiet_NaN());
  const robot::TruthTrack dr =
      reference_track(unaided, model, RangeBearingSensor(), ImplicitProposal{}, ro);
  ReferenceErrors e;
  int k = 0;
  for (std::size_t n = 0; n < p.position_fixes.size(); ++n) {
    if (!p.position_fixes[n].allFinite()) continue;
    e.gps_rmse += (p.position_fixes[n] - p.truth.position[n]).squaredNorm();
    e.reference_rmse += (ref.position[n] - p.truth.position[n]).squaredNorm();
    e.unaided_rmse += (dr.position[n] - p.truth.position[n]).squaredNorm();
    ++k;
  }
  e.gps_rmse = std::sqrt(e.gps_rmse / k);
  e.reference_rmse = std::sqrt(e.reference_rmse / k);
  e.unaided_rmse = std::sqrt(e.unaided_rmse / k);
  return e;
}

TEST(ReferenceTrack, GpsAidedReferenceIsCloserToTruthThanGps) {
  // 150 fixes with std 0.5 m: the GPS RMSE is 0.5 sqrt(2) = 0.71 m with relative standard error
  // 1 / (2 sqrt(150)) = 0.04, so it exceeds 0.71 (1 - 4.5 * 0.04) = 0.58 m with overwhelming
  // probability. With beacons (range std 0.22 m, bearing 0.03 rad at <= 20 m) the fused track is
  // a few decimetres off at most, and without them the motion model still averages ~8 fixes
  // (config B noise: ~2 cm per step), so both references must beat the fixes themselves.
  const UteModel model(low_noise());
  for (const bool beacons : {true, false}) {
    const ReferenceErrors e = reference_errors(model, beacons, 11);
    RecordProperty(beacons ? "with_beacons" : "gps_only",
                   fmt::format("gps {:.3f} reference {:.3f} unaided {:.3f}", e.gps_rmse,
                               e.reference_rmse, e.unaided_rmse));
    EXPECT_GT(e.gps_rmse, 0.58);
    EXPECT_LT(e.reference_rmse, e.gps_rmse) << "beacons " << beacons;
    EXPECT_LT(e.reference_rmse, 0.5) << "beacons " << beacons;  // within the GPS noise
    // The fixes are used: without beacons the unaided filter is dead reckoning and drifts.
    if (!beacons) {
      EXPECT_LT(e.reference_rmse, e.unaided_rmse);
    }
  }
}

// A log without truth scores nothing: the position metrics are NaN (null in the CLI's JSON, which
// --allow-empty accepts); they used to be an exception that failed every run.
TEST(LocalizationMetrics, WithoutTruthThePositionMetricsAreNaN) {
  LocalizationRun run;
  run.steps.resize(3);
  run.steps[1].updated = true;
  run.steps[1].ess = 5.0;
  run.steps[1].detections_used = 2.0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  robot::TruthTrack truth;
  truth.position.assign(3, Vec<2>(nan, nan));
  truth.heading.assign(3, nan);
  const LocalizationMetrics m = localization_metrics(run, truth, 10);
  EXPECT_TRUE(std::isnan(m.error_percent));
  EXPECT_TRUE(std::isnan(m.rmse));
  EXPECT_TRUE(std::isnan(m.max_error));
  EXPECT_EQ(m.ess_fraction, 0.5);  // what does not need truth is still there
  EXPECT_EQ(m.detections_used, 2.0);
  truth.position[2] = Vec<2>(3.0, 4.0);  // one step with truth: scored
  EXPECT_EQ(localization_metrics(run, truth, 10).rmse, 5.0);
}

}  // namespace
}  // namespace implicit::filter
