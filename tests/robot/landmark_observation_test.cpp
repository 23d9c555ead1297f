// Landmark detections as an observation model: log p(z | x) against a brute-force association
// over the whole map, the seam's derivatives against central differences, and the refusals.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/landmark_observation.hpp"

// A named namespace: the unity build compiles this file with the layer's other tests.
namespace implicit::robot::landmark_observation_test {
namespace {

using ::testing::HasSubstr;
using Model = LandmarkObservation<RangeBearingSensor>;

LandmarkMap ring_map() {
  LandmarkMap map;
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * kPi * k / 12.0;
    map.add(100 + k, Landmark(12 * std::cos(a) + 2 * std::sin(3 * a), 9 * std::sin(a)));
  }
  return map;
}

Pose random_pose(Rng& rng) {
  // One draw per declarator: the order of function arguments is unspecified.
  const double x = 8 * rng.uniform() - 4, y = 6 * rng.uniform() - 3;
  return Pose(x, y, 2 * kPi * rng.uniform() - kPi);
}

/// Detections from `x`: every third landmark seen with noise of a few standard deviations, one
/// of them labelled, plus one detection that matches nothing (clutter).
std::vector<LabelledMeasurement> detections(const Model& model, const Pose& x, Rng& rng) {
  std::vector<LabelledMeasurement> z;
  const Mat2 l = model.sensor().noise_covariance().llt().matrixL();
  for (std::size_t k = 0; k < model.map().size(); k += 3) {
    const Vec<2> xi = rng.normal_vector<2>();
    z.push_back({model.sensor().predict(x, model.map().position(k)) + 2.0 * l * xi, -1});
  }
  z[1].landmark = 3;
  z.push_back({Measurement(0.7, 0.2), -1});  // 0.7 m ahead-right: no landmark is that close
  return z;
}

/// log p(z | x) by brute force: for each unlabelled detection, every landmark at least min_range
/// away, d^2 = e^T Sigma2^-1 e by an LLT solve, the smallest d^2 inside the gate (S = Sigma2 for
/// all, so the log det S term of the ML cost is common); none: log p0.
double brute_force(const Model& model, const std::vector<LabelledMeasurement>& z, const Pose& x,
                   int& used, int& dropped) {
  const Mat2& s2 = model.sensor().noise_covariance();
  const Eigen::LLT<Mat2> llt(s2);
  const double log_norm = -std::log(2 * kPi) - 0.5 * std::log(s2.determinant());
  double total = 0.0;
  for (const LabelledMeasurement& lz : z) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < model.map().size(); ++k) {
      if (lz.landmark >= 0 && static_cast<std::size_t>(lz.landmark) != k) continue;
      const Landmark& m = model.map().position(k);
      if (lz.landmark < 0 && (m - x.head<2>()).norm() < model.association().min_range) continue;
      const Measurement e = model.sensor().residual(model.sensor().predict(x, m), lz.z);
      const double d2 = e.dot(llt.solve(e));
      if ((lz.landmark >= 0 || d2 <= model.association().gate) && d2 < best) best = d2;
    }
    if (std::isinf(best)) {
      ++dropped;
      total += -0.5 * model.association().gate + log_norm;  // p0: N on the gate boundary
    } else {
      ++used;
      total += log_norm - 0.5 * best;
    }
  }
  return total;
}

TEST(LandmarkObservation, LogLikelihoodIsTheBruteForceAssociation) {
  // Same formulas in another order (LLT solve and log det against the model's Cholesky
  // constants): 1e-12 relative is round-off of sums of ~10 terms of size ~100.
  const Model model(RangeBearingSensor(), ring_map());
  Rng rng({5, 0, 0, purpose::kUser});
  int dropped_seen = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Pose truth = random_pose(rng);
    const std::vector<LabelledMeasurement> z = detections(model, truth, rng);
    const Vec<3> offset = 0.3 * rng.normal_vector<3>();  // near the truth and further off
    for (const Pose& x : {truth, Pose(truth + offset)}) {
      int used = 0, dropped = 0;
      const double expected = brute_force(model, z, x, used, dropped);
      ObservationCounts counts;
      const double got = model.log_likelihood(model.prepare(z), x, counts);
      ASSERT_NEAR(got, expected, 1e-12 * std::max(1.0, std::abs(expected))) << trial;
      EXPECT_EQ(counts.used, used) << trial;
      EXPECT_EQ(counts.dropped, dropped) << trial;
      EXPECT_EQ(model.log_likelihood(model.prepare(z), x), got);
      dropped_seen += dropped;
    }
  }
  EXPECT_GE(dropped_seen, 400);  // the clutter detection, at least, every time
}

TEST(LandmarkObservation, ClutterOffDropsWithoutATerm) {
  AssociationOptions a;
  a.clutter = false;
  const Model model(RangeBearingSensor(), ring_map(), a);
  const std::vector<LabelledMeasurement> z{{Measurement(0.7, 0.2), -1}};
  ObservationCounts counts;
  EXPECT_EQ(model.log_likelihood(model.prepare(z), Pose(0, 0, 0), counts), 0.0);
  EXPECT_EQ(counts.dropped, 1);
  EXPECT_EQ(model.log_clutter(),
            clutter_log_density(a.gate, RangeBearingSensor().noise_covariance()));
}

TEST(LandmarkObservation, NegativeLogLikelihoodAndItsDerivatives) {
  // -log p equals the negated log_likelihood (1e-12 relative, round-off). The gradient against
  // central differences with h = 1e-6: truncation h^2 |F'''| / 6 ~ 1e-12 * 1e3, round-off
  // eps |F| / h ~ 1e-16 * 1e3 / 1e-6 = 1e-7; 1e-5 relative covers both. The Gauss-Newton matrix
  // against sum J^T Sigma2^-1 J with J by central differences of the predictions (same bounds).
  const Model model(RangeBearingSensor(), ring_map());
  Rng rng({6, 0, 0, purpose::kUser});
  const Mat2 info = model.sensor().noise_covariance().inverse();
  for (int trial = 0; trial < 50; ++trial) {
    const Pose x = random_pose(rng);
    const std::vector<LabelledMeasurement> z = detections(model, x, rng);
    const auto d = model.prepare(z);
    const Vec<3> g0(1.0, -2.0, 3.0);
    const Mat3 h0 = Mat3::Identity();
    Vec<3> g = g0;
    Mat3 gn = h0;
    const double f = model.negative_log_likelihood(d, x, &g, &gn);
    ASSERT_NEAR(f, -model.log_likelihood(d, x), 1e-12 * std::max(1.0, std::abs(f)));
    EXPECT_EQ(model.negative_log_likelihood(d, x, nullptr, nullptr), f);
    Mat3 expected_gn = h0;
    constexpr double kH = 1e-6;
    for (int i = 0; i < 3; ++i) {
      const Vec<3> step = kH * Vec<3>::Unit(i);
      const double fd = (model.negative_log_likelihood(d, x + step, nullptr, nullptr) -
                         model.negative_log_likelihood(d, x - step, nullptr, nullptr)) /
                        (2 * kH);
      EXPECT_NEAR(g(i) - g0(i), fd, 1e-5 * std::max(1.0, std::abs(fd))) << trial << " " << i;
    }
    for (const LabelledMeasurement& lz : z) {
      const int k = lz.landmark >= 0 ? lz.landmark : model.associate(x, nullptr, lz.z);
      if (k < 0) continue;
      const Landmark& m = model.map().position(static_cast<std::size_t>(k));
      Mat23 j;
      for (int i = 0; i < 3; ++i) {
        const Vec<3> step = kH * Vec<3>::Unit(i);
        j.col(i) = model.sensor().residual(model.sensor().predict(x + step, m),
                                           model.sensor().predict(x - step, m)) /
                   (2 * kH);
      }
      expected_gn += j.transpose() * info * j;
    }
    const double scale = std::max(1.0, expected_gn.cwiseAbs().maxCoeff());
    EXPECT_LE((gn - expected_gn).cwiseAbs().maxCoeff(), 1e-5 * scale) << trial;
  }
  EXPECT_TRUE(model.differentiable());
}

TEST(LandmarkObservation, PredictiveCovarianceWidensTheGate) {
  // A detection 1 m off in range: d^2 = 1 / 0.05 = 20 > gate with S = Sigma2, but with a pose
  // covariance of 1 m^2 per axis S_00 = 1.05 and it is associated.
  LandmarkMap map;
  map.add(0, Landmark(0, 10));
  const Model model(RangeBearingSensor(), map);
  const Pose x(0, 0, kPi / 2);  // looking north: the landmark is straight ahead, bearing pi/2
  const Measurement z(11.0, kPi / 2);
  EXPECT_EQ(model.associate(x, nullptr, z), -1);
  const Mat3 pose_cov = Vec<3>(1.0, 1.0, 0.0).asDiagonal();
  EXPECT_EQ(model.associate(x, &pose_cov, z), 0);
}

/// A sensor whose noise matrix is not positive definite.
struct IndefiniteSensor {
  RangeBearingSensor base = RangeBearingSensor();
  Mat2 noise = (Mat2() << 1.0, 2.0, 2.0, 1.0).finished();
  Measurement predict(const Pose& x, const Landmark& m) const { return base.predict(x, m); }
  static Measurement residual(const Measurement& a, const Measurement& b) {
    return RangeBearingSensor::residual(a, b);
  }
  Mat23 jacobian_pose(const Pose& x, const Landmark& m) const { return base.jacobian_pose(x, m); }
  const Mat2& noise_covariance() const { return noise; }
};

TEST(LandmarkObservation, RefusesBadModelsAndDetectionsNamingWhere) {
  AssociationOptions a;
  a.gate = 0.0;
  EXPECT_THROW((void)Model(RangeBearingSensor(), ring_map(), a), InvalidArgument);
  EXPECT_THROW((void)LandmarkObservation<IndefiniteSensor>(IndefiniteSensor{}, ring_map()),
               InvalidArgument);
  const Model model(RangeBearingSensor(), ring_map());
  auto message = [&](const std::vector<LabelledMeasurement>& z) -> std::string {
    try {
      (void)model.prepare(z, "log.txt:7");
    } catch (const InvalidArgument& e) {
      return e.what();
    }
    return "no error";
  };
  const std::vector<LabelledMeasurement> many(kMaxDetectionsPerStep + 1,
                                              LabelledMeasurement{Measurement(5, 1), -1});
  EXPECT_THAT(message(many), HasSubstr("log.txt:7: expected at most 32 detections per step"));
  EXPECT_THAT(message({{Measurement(5, std::nan("")), -1}}),
              HasSubstr("log.txt:7: expected finite"));
  EXPECT_THAT(message({{Measurement(5, 1), 12}}), HasSubstr("landmark index below 12"));
  EXPECT_EQ(message({{Measurement(5, 1), 11}, {Measurement(5, 1), -1}}), "no error");
  // view() checks nothing (a global start reads any number of detections).
  EXPECT_EQ(model.view(many).size(), many.size());
}

}  // namespace
}  // namespace implicit::robot::landmark_observation_test
