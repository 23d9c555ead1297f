// Spatial index for maximum-likelihood association: the indexed search must return exactly the
// association of the linear scan, and its search disc must contain every landmark inside the gate.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/ute_model.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/landmark_index.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {
namespace {

using robot::RangeBearingSensor;

// A random SPD 2x2 covariance with trace <= max_trace.
Mat<2> random_cov(Rng& rng, double max_trace) {
  const double a = rng.uniform(), b = rng.uniform(), c = rng.uniform() - 0.5;
  Mat<2> l;
  l << a, 0.0, c, b;
  Mat<2> p = l * l.transpose() + 1e-6 * Mat<2>::Identity();
  return p * (max_trace * rng.uniform() / p.trace());
}

// One random association problem: a map with landmarks around the pose, many of them placed on
// or within 1e-12 m of cell borders, and a detection of one of them (or of nothing).
struct Case {
  LandmarkEstimates map;
  LandmarkGridIndex index;
  double trace_bound = 0.0;
  Pose f = Pose::Zero();
  Mat<3> sigma1 = Mat<3>::Zero();
  Measurement z = Measurement::Zero();
};

Case make_case(std::uint64_t k) {
  Rng rng({11, k, 0, purpose::kData});
  Case c;
  const double cell = c.index.cell_size();
  // One draw per declarator or statement: the order of function arguments is unspecified, and
  // the cases must be the same for every compiler.
  const double fx = 40.0 * (rng.uniform() - 0.5), fy = 40.0 * (rng.uniform() - 0.5);
  c.f = Pose(fx, fy, 6.0 * rng.uniform());
  const robot::UteModel model{robot::UteParams{}};
  const double speed = 0.5 + 3.0 * rng.uniform();
  const Control u(speed, 0.4 * (rng.uniform() - 0.5));
  // Scale Sigma1 up to 100x so that the disc bound is exercised with large pose uncertainty.
  const double scale = 99.0 * rng.uniform();
  c.sigma1 = model.process_covariance(c.f, u) * (1.0 + scale * rng.uniform());
  const double max_trace = k % 3 == 0 ? 0.0 : (k % 3 == 1 ? 0.3 : 5.0);
  const int n = 30 + static_cast<int>(rng.uniform() * 300);
  for (int i = 0; i < n; ++i) {
    const double dx = 50.0 * (rng.uniform() - 0.5), dy = 50.0 * (rng.uniform() - 0.5);
    Vec<2> m = c.f.head<2>() + Vec<2>(dx, dy);
    const double v = rng.uniform();
    if (v < 0.3) m(0) = cell * std::round(m(0) / cell);  // on a vertical border
    if (v > 0.2 && v < 0.5) m(1) = cell * std::round(m(1) / cell);
    if (v > 0.9) m(0) = cell * std::round(m(0) / cell) + (rng.uniform() < 0.5 ? -1e-12 : 1e-12);
    const LandmarkEstimate l{m, random_cov(rng, max_trace)};
    c.map.push_back(l);
    c.index.insert(static_cast<std::uint32_t>(i), m, l.cov.trace());
    c.trace_bound = std::max(c.trace_bound, l.cov.trace());
  }
  const RangeBearingSensor s;
  if (rng.uniform() < 0.8) {
    const auto target = static_cast<std::size_t>(rng.uniform() * static_cast<double>(n));
    const Vec<2> noise = Vec<2>(0.3, 0.05).cwiseProduct(rng.normal_vector<2>());
    c.z = s.predict(c.f, c.map.get(std::min(target, c.map.size() - 1)).mean) + noise;
  } else {
    const double range = 1.0 + 14.0 * rng.uniform();
    c.z = Measurement(range, kPi * rng.uniform());
  }
  c.z(0) = std::max(c.z(0), 0.05);
  return c;
}

TEST(LandmarkIndex, IndexedAssociationEqualsLinearScanOnRandomCases) {
  const RangeBearingSensor s;
  int matched = 0;
  for (std::uint64_t k = 0; k < 3000; ++k) {
    const Case c = make_case(k);
    const double gate = k % 2 ? 9.21 : 30.0;
    std::vector<std::uint32_t> scratch;
    const auto scan = associate_scan(c.map, s, c.f, c.sigma1, c.z, gate);
    const auto idx = associate_indexed(c.map, c.index, s, c.f, c.sigma1, c.z, gate, scratch);
    ASSERT_EQ(scan.index, idx.index) << "case " << k;
    if (scan.matched()) {
      ASSERT_EQ(scan.mahalanobis2, idx.mahalanobis2) << "case " << k;
      ++matched;
    }
    // The scan without the cheap range check (plain gate) agrees as well.
    const auto plain = robot::associate_max_likelihood(
        static_cast<int>(c.map.size()),
        [&](int i, Measurement& e, Mat<2>& sk) {
          const LandmarkEstimate& l = c.map.get(static_cast<std::size_t>(i));
          e = RangeBearingSensor::residual(s.predict(c.f, l.mean), c.z);
          const robot::Mat23 hx = s.jacobian_pose(c.f, l.mean);
          const Mat<2> hm = -hx.leftCols<2>();
          sk = hx * c.sigma1 * hx.transpose() + hm * l.cov * hm.transpose() + s.noise_covariance();
          return true;
        },
        gate);
    ASSERT_EQ(plain.index, scan.index) << "case " << k;
  }
  // Most detections come from a landmark: the comparison must not be vacuous.
  EXPECT_GT(matched, 1500);
}

TEST(LandmarkIndex, SearchDiscContainsEveryLandmarkInsideTheGate) {
  const RangeBearingSensor s;
  std::size_t inside_gate = 0;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    const Case c = make_case(k + 10000);
    const SearchDisc disc = association_search_disc(s, c.f, c.sigma1, c.z, c.trace_bound, 9.21);
    c.map.for_each([&](std::size_t i, const LandmarkEstimate& l) {
      const Measurement e = RangeBearingSensor::residual(s.predict(c.f, l.mean), c.z);
      const robot::Mat23 hx = s.jacobian_pose(c.f, l.mean);
      const Mat<2> hm = -hx.leftCols<2>();
      const Mat<2> sk =
          hx * c.sigma1 * hx.transpose() + hm * l.cov * hm.transpose() + s.noise_covariance();
      double d2 = 0, log_det = 0;
      if (!robot::innovation_statistics(e, sk, d2, log_det) || d2 > 9.21) return;
      ++inside_gate;
      ASSERT_LE((l.mean - disc.center).norm(), disc.radius) << "case " << k << " slot " << i;
      const double range = (l.mean - c.f.head<2>()).norm();
      ASSERT_LE(std::abs(range - c.z(0)), disc.range_margin) << "case " << k << " slot " << i;
    });
  }
  EXPECT_GT(inside_gate, 1000u);
}

TEST(LandmarkIndex, MovedLandmarksAndSharedSlotsStayFindable) {
  // Two "particles" share slots 0..n-1, then each moves a landmark into another cell and one
  // creates slot n at a place where the other has nothing.
  const RangeBearingSensor s;
  LandmarkGridIndex index;
  LandmarkEstimates a;
  for (int i = 0; i < 40; ++i) {
    const Vec<2> m(2.0 * i, i % 2 ? 5.0 : -5.0);
    // Landmark 20 starts wide (covariance class 3), the others narrow (class 0).
    const Mat<2> cov = (i == 20 ? 3.0 : 0.01) * Mat<2>::Identity();
    a.push_back({m, cov});
    index.insert(static_cast<std::uint32_t>(i), m, cov.trace());
  }
  EXPECT_EQ(index.max_class(), 3);
  LandmarkEstimates b = a;
  LandmarkEstimate moved = b.get(10);
  moved.mean += Vec<2>(0.0, 9.0);  // from y = -5 to y = 4: another cell
  b.set(10, moved);
  index.insert(10, moved.mean, moved.cov.trace());
  LandmarkEstimate shrunk = b.get(20);  // an update: class 3 -> class 0, a small move
  shrunk.mean += Vec<2>(0.3, 0.2);
  shrunk.cov = 0.01 * Mat<2>::Identity();
  EXPECT_FALSE(
      index.same_bucket(shrunk.mean, shrunk.cov.trace(), b.get(20).mean, b.get(20).cov.trace()));
  b.set(20, shrunk);
  index.insert(20, shrunk.mean, shrunk.cov.trace());
  a.push_back({Vec<2>(30.0, 30.0), 0.01 * Mat<2>::Identity()});
  index.insert(40, Vec<2>(30.0, 30.0), 0.02);
  EXPECT_EQ(a.get(10).mean, Vec<2>(20.0, -5.0));  // the other particle is untouched
  const Mat<3> sigma1 = 1e-4 * Mat<3>::Identity();
  std::vector<std::uint32_t> scratch;
  for (const LandmarkEstimates* map : {&a, &b})
    for (double x = -2.0; x < 82.0; x += 1.7)
      for (double bearing = 0.0; bearing <= kPi; bearing += 0.2) {
        const Pose f(x, 0.0, kPi / 2);
        const Measurement z(5.5, bearing);
        const auto scan = associate_scan(*map, s, f, sigma1, z, 9.21);
        const auto idx = associate_indexed(*map, index, s, f, sigma1, z, 9.21, scratch);
        ASSERT_EQ(scan.index, idx.index) << x << " " << bearing;
      }
  // The moved landmark is found where particle b has it, and not where it was.
  const auto hit =
      associate_indexed(b, index, s, Pose(20.0, 0.0, kPi / 2), 1e-4 * Mat<3>::Identity(),
                        Measurement(4.0, kPi / 2), 9.21, scratch);
  EXPECT_EQ(hit.index, 10);
}

TEST(LandmarkIndex, BadCellSizeAndNonFinitePositions) {
  EXPECT_THROW(LandmarkGridIndex(0.0), InvalidArgument);
  EXPECT_THROW(LandmarkGridIndex(-1.0), InvalidArgument);
  LandmarkGridIndex index;
  index.insert(0, Vec<2>(std::nan(""), 1.0), 0.0);
  EXPECT_EQ(index.entries(), 0u);
  EXPECT_EQ(index.max_class(), -1);
  index.insert(1, Vec<2>(1.0, 1.0), 0.1);
  index.insert(1, Vec<2>(1.5, 1.5), 0.2);  // same class and cell, same slot: registered once
  EXPECT_EQ(index.entries(), 1u);
  // Covariance classes: trace <= 0.25 * 4^c, boundaries included in the lower class.
  EXPECT_EQ(LandmarkGridIndex::covariance_class(0.0), 0);
  EXPECT_EQ(LandmarkGridIndex::covariance_class(0.25), 0);
  EXPECT_EQ(LandmarkGridIndex::covariance_class(0.2500001), 1);
  EXPECT_EQ(LandmarkGridIndex::covariance_class(1.0), 1);
  EXPECT_EQ(LandmarkGridIndex::covariance_class(5.0), 3);
  for (double t : {0.3, 1.0, 3.9, 4.0, 4.1, 1e3})
    EXPECT_LE(t, LandmarkGridIndex::class_trace(LandmarkGridIndex::covariance_class(t))) << t;
}

TEST(SlamMetrics, MapShapeIsZeroForARigidlyMovedMap) {
  // Closed form: the estimate is the true map rotated by 0.2 rad and shifted; the shape error
  // after the rigid alignment must vanish, the raw error must not.
  SlamDataset d;
  SlamDatasetBuilder b(d);
  d.initial_pose = Pose(0, 0, 0);
  d.landmarks = {Vec<2>(1, 2), Vec<2>(5, -1), Vec<2>(-3, 4), Vec<2>(7, 7)};
  b.begin_step(Control(1, 0));
  d.truth = {Pose(0, 0, 0), Pose(1, 0, 0)};
  SlamRun run;
  run.path = d.truth;
  run.path_cov.assign(2, Mat<3>::Identity());
  Mat<2> r;
  r << std::cos(0.2), -std::sin(0.2), std::sin(0.2), std::cos(0.2);
  for (std::size_t k = 0; k < d.landmarks.size(); ++k) {
    run.map.landmarks.push_back(r * d.landmarks[k] + Vec<2>(3, -2));
    run.map.ids.push_back(static_cast<int>(k));
  }
  const SlamMetrics m = evaluate(d, run);
  EXPECT_LT(m.map_shape_m, 1e-12);
  EXPECT_GT(m.rmse_map_m, 1.0);
  EXPECT_NEAR(m.alignment_angle_rad, -0.2, 1e-12);
}

TEST(SlamMetrics, WithoutATrueMapThePathIsAlignedOnItsOwn) {
  // Real data (GPS, no surveyed map): a path that is the truth rotated and shifted has no error
  // after alignment, while the raw error is the shift and rotation.
  SlamDataset d;
  SlamDatasetBuilder b(d);
  d.initial_pose = Pose(0, 0, 0);
  d.truth = {Pose(0, 0, 0)};
  for (int n = 1; n <= 20; ++n) {
    b.begin_step(Control(1, 0));
    d.truth.push_back(Pose(n, 0.1 * n * n, 0));
  }
  d.truth_has_heading = false;
  SlamRun run;
  Mat<2> r;
  r << std::cos(0.3), -std::sin(0.3), std::sin(0.3), std::cos(0.3);
  for (const Pose& t : d.truth) {
    Pose e = t;
    e.head<2>() = r * t.head<2>() + Vec<2>(-4, 2);
    run.path.push_back(e);
  }
  run.path_cov.assign(d.truth.size(), Mat<3>::Identity());
  const SlamMetrics m = evaluate(d, run);
  EXPECT_LT(m.rmse_pose_aligned_m, 1e-9);
  EXPECT_LT(m.error_aligned_percent, 1e-9);
  EXPECT_GT(m.rmse_pose_m, 4.0);
  EXPECT_NEAR(m.alignment_angle_rad, -0.3, 1e-12);
}

}  // namespace
}  // namespace implicit::slam

namespace implicit::slam {
namespace {

TEST(LandmarkIndex, FilterGivesTheSamePathWithIndexAndScan) {
  // 2 000 known landmarks (above the map size where the filter switches to the index), ML
  // association, 150 steps: the index must not change a single bit of the estimate, with one
  // thread or two (the shared index is only written between the parallel particle loops).
  const SlamScenario base = load_carpark_scenario(default_data_dir());
  const SlamScenario sc = make_dense_scenario(base, 1, 2000, 3);
  SlamDataset d = generate_synthetic(sc, SyntheticConfig(), 2);
  for (SlamMethod m : {SlamMethod::kFastSlam2, SlamMethod::kImplicitRb}) {
    std::vector<Pose> path[3];
    std::size_t created[3] = {0, 0, 0};
    for (int idx = 0; idx < 3; ++idx) {
      const ThreadLimit threads(idx == 2 ? 2 : 1);
      SlamOptions opt;
      opt.method = m;
      opt.association = Association::kMaximumLikelihood;
      opt.association_index = idx >= 1;
      opt.particles = 20;
      auto f = make_slam_filter(opt, d.initial_pose);
      f->set_known_map(d.landmarks);
      for (std::size_t n = 1; n <= 150; ++n) {
        f->step(n, d.control(n), d.observations(n));
        path[idx].push_back(f->pose().mean);
      }
      created[idx] = f->stats().new_landmarks;
      EXPECT_GT(f->stats().updates, 100u);  // detections really were associated
    }
    EXPECT_EQ(created[0], created[1]);
    EXPECT_EQ(created[0], created[2]);
    for (std::size_t n = 0; n < path[0].size(); ++n) {
      ASSERT_EQ(path[0][n], path[1][n]) << to_string(m) << " step " << n;
      ASSERT_EQ(path[1][n], path[2][n]) << to_string(m) << " two threads, step " << n;
    }
  }
}

}  // namespace
}  // namespace implicit::slam
