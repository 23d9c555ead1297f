// Global localization: the modes of -log p(z | x) on a symmetric and a labelled map, exact
// importance weights against a 3-D grid integral, determinism over thread counts, errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "implicit/core/parallel.hpp"
#include "implicit/filter/global_localization.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::filter {
namespace {

using robot::RangeBearingSensor;
using Model = robot::LandmarkObservation<RangeBearingSensor>;
using Detections = robot::LandmarkDetections<RangeBearingSensor>;

/// The landmark model as the particle filter builds it (default association: 99 % gate, clutter
/// on), with the map's indices as ids.
Model make_model(const RangeBearingSensor& sensor, const std::vector<Landmark>& map) {
  robot::LandmarkMap m;
  for (std::size_t i = 0; i < map.size(); ++i) m.add(static_cast<int>(i), map[i]);
  return Model(sensor, m);
}

/// Exact detections of every landmark from `truth`; label = index, or -1 when unlabelled.
std::vector<LabelledMeasurement> observe(const RangeBearingSensor& sensor,
                                         const std::vector<Landmark>& map, const Pose& truth,
                                         bool labelled) {
  std::vector<LabelledMeasurement> z;
  for (std::size_t i = 0; i < map.size(); ++i)
    z.push_back({sensor.predict(truth, map[i]), labelled ? static_cast<int>(i) : -1});
  return z;
}

const std::vector<Landmark> kSquare = {Landmark(10, 10), Landmark(-10, 10), Landmark(-10, -10),
                                       Landmark(10, -10)};

TEST(GlobalLocalization, SymmetricSquareHasFourEqualModes) {
  const RangeBearingSensor sensor;
  const auto z = observe(sensor, kSquare, Pose(0, 0, 0), false);
  const Model model = make_model(sensor, kSquare);
  const Detections ctx = model.view(z);
  GlobalInitStats st;
  const auto modes = find_pose_modes(ctx, map_bounds(kSquare, 5.0), GlobalInitOptions{}, &st);
  ASSERT_GE(modes.size(), 4u);
  // Exact data: the best phi is the constant of 4 associated terms, 4 (log 2pi + 1/2 log det S2).
  EXPECT_NEAR(modes[0].phi, 4.0 * (kLog2Pi + 0.5 * model.log_det_noise()), 1e-9);
  std::size_t best = 0;
  while (best < modes.size() && modes[best].phi <= modes[0].phi + 1e-6) ++best;
  EXPECT_EQ(best, 4u);
  std::vector<double> headings = {0.0, kPi / 2, kPi, -kPi / 2};
  for (std::size_t k = 0; k < std::min<std::size_t>(best, 4); ++k) {
    EXPECT_NEAR(modes[k].mu(0), 0.0, 1e-6);
    EXPECT_NEAR(modes[k].mu(1), 0.0, 1e-6);
    EXPECT_GE(modes[k].mu(2), -kPi);
    EXPECT_LT(modes[k].mu(2), kPi);
    for (std::size_t h = 0; h < headings.size(); ++h)
      if (std::abs(wrap_angle(modes[k].mu(2) - headings[h])) < 1e-6) {
        headings.erase(headings.begin() + static_cast<long>(h));
        break;
      }
  }
  EXPECT_TRUE(headings.empty()) << headings.size() << " symmetric headings not found";
  EXPECT_EQ(st.starts, 15u * 15u * 8u);  // box [-15, 15]^2, spacing 2 m: 15 x 15 cells
  EXPECT_EQ(st.modes, modes.size());
}

TEST(GlobalLocalization, LabelledDetectionsGiveOneMode) {
  const RangeBearingSensor sensor;
  const Pose truth(2.0, -3.0, 0.7);
  const auto z = observe(sensor, kSquare, truth, true);
  GlobalInitStats st;
  const Model model = make_model(sensor, kSquare);
  const auto modes =
      find_pose_modes(model.view(z), map_bounds(kSquare, 5.0), GlobalInitOptions{}, &st);
  // Other local minima exist (wrapped bearings), with phi ~1e4 above: weight ratio exp(-1e4).
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_GE(st.negligible, 1u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(modes[0].mu(i), truth(i), 1e-8) << "entry " << i;
}

// A small labelled map with noisy detections: one mode, broad enough (range std 0.3 m, bearing std
// 0.15 rad) that the Laplace approximation is visibly off, with the heading near pi so that drawn
// headings wrap. The grid integrates t = u p over +-10 Laplace std devs around the mode.
struct SmallMap {
  RangeBearingSensor sensor{0.09, 0.0225};
  std::vector<Landmark> map = {Landmark(0, 4), Landmark(4, 0), Landmark(-3, -3)};
  std::vector<LabelledMeasurement> z;
  Model model = make_model(sensor, map);
  Detections ctx;
  PoseBounds bounds = map_bounds(map, 2.0);
  SmallMap() {
    z = observe(sensor, map, Pose(0.5, 0.3, 3.05), true);
    z[0].z += Measurement(0.2, -0.1);
    z[1].z += Measurement(-0.15, 0.05);
    z[2].z += Measurement(0.1, 0.12);
    ctx = model.view(z);
  }
  SmallMap(const SmallMap&) = delete;  // ctx points into it
};

/// Z and the posterior mean by the grid against the weights of N = 20000 draws with the given
/// defensive uniform fraction.
void check_weights_against_grid(double uniform_fraction) {
  const SmallMap s;
  const auto modes = find_pose_modes(s.ctx, s.bounds, GlobalInitOptions{});
  ASSERT_EQ(modes.size(), 1u);
  const Laplace<3>& mode = modes[0];
  // Marginal std devs of the Laplace approximation: sqrt(diag(H^-1)), H^-1 = L^-T L^-1.
  const Mat3 linv = mode.L.triangularView<Eigen::Lower>().solve(Mat3::Identity());
  const Vec<3> sd = (linv.transpose() * linv).diagonal().cwiseSqrt();
  ASSERT_LT(10.0 * sd(2), kPi);
  constexpr int kGrid = 161;  // trapezoid, exact up to spectral accuracy for a smooth bump
  Vec<3> h;
  for (int i = 0; i < 3; ++i) h(i) = 20.0 * sd(i) / (kGrid - 1);
  const double log_u = log_uniform_density(s.bounds);
  double z = 0.0;
  Vec<3> moment = Vec<3>::Zero();  // of (x, y, heading offset from mu wrapped)
  for (int a = 0; a < kGrid; ++a)
    for (int b = 0; b < kGrid; ++b)
      for (int c = 0; c < kGrid; ++c) {
        const Vec<3> d((a - kGrid / 2) * h(0), (b - kGrid / 2) * h(1), (c - kGrid / 2) * h(2));
        Pose x = mode.mu + d;
        x(2) = wrap_angle(x(2));
        if (!s.bounds.contains(x)) continue;
        const double t = std::exp(log_u + s.model.log_likelihood(s.ctx, x));
        z += t;
        moment += t * Vec<3>(x(0), x(1), d(2));
      }
  const Vec<3> grid_mean = moment / z;
  z *= h.prod();

  constexpr std::size_t kN = 20000;
  std::vector<Pose> particles(kN);
  std::vector<double> log_w(kN);
  sample_pose_mixture(s.ctx, modes, s.bounds, 11, 0, particles, log_w, uniform_fraction);
  double sum = 0.0, sum2 = 0.0;
  Vec<3> wx = Vec<3>::Zero();
  std::vector<Vec<3>> offsets(kN);
  for (std::size_t j = 0; j < kN; ++j) {
    ASSERT_GE(particles[j](2), -kPi);
    ASSERT_LT(particles[j](2), kPi);
    const double w = std::exp(log_w[j]);
    offsets[j] = Vec<3>(particles[j](0), particles[j](1), wrap_angle(particles[j](2) - mode.mu(2)));
    sum += w;
    sum2 += w * w;
    wx += w * offsets[j];
  }
  const double n = static_cast<double>(kN), mean = sum / n;
  const double se = std::sqrt((sum2 / n - mean * mean) / (n - 1.0));
  EXPECT_NEAR(mean, z, 4.5 * se) << "Z by the grid " << z << ", by the weights " << mean;
  // Self-normalised mean: delta-method SE sqrt(sum w^2 (x - m)^2) / sum w.
  const Vec<3> m = wx / sum;
  Vec<3> var = Vec<3>::Zero();
  for (std::size_t j = 0; j < kN; ++j) {
    const double w = std::exp(log_w[j]);
    var += (w * w) * (offsets[j] - m).cwiseAbs2();
  }
  const Vec<3> se_mean = var.cwiseSqrt() / sum;
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(m(i), grid_mean(i), 4.5 * se_mean(i)) << "mean entry " << i;
  std::printf(
      "Z grid %.6g weights %.6g +- %.2g; mean grid (%.5f %.5f %.5f) weights (%.5f %.5f %.5f)"
      " +- (%.2g %.2g %.2g); Laplace sd (%.3g %.3g %.3g)\n",
      z, mean, se, grid_mean(0), grid_mean(1), grid_mean(2), m(0), m(1), m(2), se_mean(0),
      se_mean(1), se_mean(2), sd(0), sd(1), sd(2));
}

TEST(GlobalLocalization, WeightsAreExactAgainstGridIntegral) { check_weights_against_grid(0.0); }

TEST(GlobalLocalization, WeightsWithUniformComponentAreExact) { check_weights_against_grid(0.3); }

// The wrapped mixture density against the brute-force sum over 101 shifts, for a narrow and a
// wide (heading std 2.5 rad, correlated with x) component.
TEST(GlobalLocalization, WrappedDensityMatchesSumOverShifts) {
  Mat3 h1, h2;
  h1 << 40.0, 5.0, 3.0, 5.0, 30.0, -2.0, 3.0, -2.0, 400.0;
  h2 << 2.0, 0.0, 0.3, 0.0, 1.0, 0.0, 0.3, 0.0, 0.2;
  const Laplace<3> a = Laplace<3>::make(Vec<3>(1.0, 2.0, 3.0), 0.5, h1);
  const Laplace<3> b = Laplace<3>::make(Vec<3>(1.5, 1.0, -0.5), 1.5, h2);
  ASSERT_GT(1.0 / b.L(2, 2), 2.0);
  const MixtureProposal<3> mix({a, b});
  const detail::WrappedMixture q(mix);
  for (const Pose& x : {Pose(1.0, 2.0, 3.1), Pose(1.1, 1.9, -3.1), Pose(0.0, 0.0, 0.0),
                        Pose(2.0, 1.0, -2.5), Pose(1.5, 1.0, 1.0)}) {
    std::vector<double> terms;
    for (int n = -50; n <= 50; ++n) terms.push_back(mix.log_density(x + Vec<3>(0, 0, 2 * kPi * n)));
    EXPECT_NEAR(q.log_density(x), log_sum_exp(terms), 1e-12) << x.transpose();
  }
}

TEST(GlobalLocalization, SameNumbersForOneAndTwoThreads) {
  const RangeBearingSensor sensor;
  const auto z = observe(sensor, kSquare, Pose(1.0, 2.0, 0.3), false);
  const Model model = make_model(sensor, kSquare);
  const Detections ctx = model.view(z);
  const PoseBounds b = map_bounds(kSquare, 5.0);
  auto run = [&](int threads, std::vector<Laplace<3>>& modes, std::vector<Pose>& x,
                 std::vector<double>& lw) {
    const ThreadLimit limit(threads);
    modes = find_pose_modes(ctx, b, GlobalInitOptions{});
    x.resize(3000);
    lw.resize(3000);
    sample_pose_mixture(ctx, modes, b, 5, 2, x, lw);
  };
  std::vector<Laplace<3>> m1, m2;
  std::vector<Pose> x1, x2;
  std::vector<double> w1, w2;
  run(1, m1, x1, w1);
  run(2, m2, x2, w2);
  ASSERT_EQ(m1.size(), m2.size());
  ASSERT_GE(m1.size(), 4u);
  for (std::size_t k = 0; k < m1.size(); ++k) {
    EXPECT_EQ(m1[k].phi, m2[k].phi);
    EXPECT_EQ(std::memcmp(m1[k].mu.data(), m2[k].mu.data(), sizeof(double) * 3), 0);
    EXPECT_EQ(std::memcmp(m1[k].L.data(), m2[k].L.data(), sizeof(double) * 9), 0);
  }
  EXPECT_EQ(std::memcmp(x1.data(), x2.data(), sizeof(Pose) * x1.size()), 0);
  EXPECT_EQ(std::memcmp(w1.data(), w2.data(), sizeof(double) * w1.size()), 0);
}

TEST(GlobalLocalization, Errors) {
  const RangeBearingSensor sensor;
  const auto z = observe(sensor, kSquare, Pose(0, 0, 0), false);
  const Model model = make_model(sensor, kSquare);
  const Detections ctx = model.view(z);
  std::vector<Pose> x(4);
  std::vector<double> lw(4);
  try {
    sample_pose_mixture(ctx, {}, map_bounds(kSquare, 1.0), 1, 0, x, lw);
    ADD_FAILURE() << "no error for empty modes";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("no pose explains the detections"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(map_bounds({}, 5.0), InvalidArgument);
  EXPECT_THROW(map_bounds(std::vector<Landmark>{Landmark(1, 2)}, 0.0), InvalidArgument);
  GlobalInitOptions o;
  o.cover_spacing = 0.0;
  EXPECT_THROW(find_pose_modes(ctx, map_bounds(kSquare, 1.0), o), InvalidArgument);
}

TEST(GlobalLocalization, MapBoundsAndUniformCloud) {
  const PoseBounds b = map_bounds(kSquare, 5.0);
  EXPECT_EQ(b.x_min, -15.0);
  EXPECT_EQ(b.x_max, 15.0);
  EXPECT_EQ(b.y_min, -15.0);
  EXPECT_EQ(b.y_max, 15.0);
  EXPECT_DOUBLE_EQ(log_uniform_density(b), -std::log(900.0 * 2.0 * kPi));
  constexpr std::size_t kN = 20000;
  std::vector<Pose> x(kN);
  sample_uniform_poses(b, 3, x);
  Vec<3> mean = Vec<3>::Zero();
  for (const Pose& p : x) {
    ASSERT_TRUE(b.contains(p));
    ASSERT_GE(p(2), -kPi);
    ASSERT_LT(p(2), kPi);
    mean += p / static_cast<double>(kN);
  }
  // Uniform on [-a, a]: mean 0, std a / sqrt(3).
  const Vec<3> se = Vec<3>(15.0, 15.0, kPi) / std::sqrt(3.0 * kN);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(mean(i), 0.0, 4.5 * se(i)) << "entry " << i;
}

}  // namespace
}  // namespace implicit::filter
