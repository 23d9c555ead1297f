// Global localization: the modes of -log p(z | x) on a symmetric and a labelled map, exact
// importance weights against a 3-D grid integral, determinism over thread counts, errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "implicit/core/parallel.hpp"
#include "implicit/filter/global_localization.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::filter {
namespace {

using robot::RangeBearingSensor;
using Ctx = ProposalContext<robot::UteModel, RangeBearingSensor>;

/// A context as the particle filter builds it (default association: 99 % gate, clutter on).
Ctx make_context(const RangeBearingSensor& sensor, const std::vector<Landmark>& map,
                 const std::vector<LabelledMeasurement>& z) {
  Ctx ctx;
  ctx.sensor = &sensor;
  ctx.map = map;
  const Mat2& noise = sensor.noise_covariance();
  const Eigen::LLT<Mat2> llt(noise);
  ctx.noise_information = llt.solve(Mat2::Identity());
  ctx.log_det_noise = 2.0 * std::log(llt.matrixL()(0, 0) * llt.matrixL()(1, 1));
  ctx.log_clutter = robot::clutter_log_density(ctx.association.gate, noise);
  ctx.z = z;
  return ctx;
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
  const Ctx ctx = make_context(sensor, kSquare, z);
  GlobalInitStats st;
  const auto modes = find_pose_modes(ctx, map_bounds(kSquare, 5.0), GlobalInitOptions{}, &st);
  ASSERT_GE(modes.size(), 4u);
  // Exact data: the best phi is the constant of 4 associated terms, 4 (log 2pi + 1/2 log det S2).
  EXPECT_NEAR(modes[0].phi, 4.0 * (kLog2Pi + 0.5 * ctx.log_det_noise), 1e-9);
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
  const auto modes = find_pose_modes(make_context(sensor, kSquare, z), map_bounds(kSquare, 5.0),
                                     GlobalInitOptions{});
  ASSERT_EQ(modes.size(), 1u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(modes[0].mu(i), truth(i), 1e-8) << "entry " << i;
}

}  // namespace
}  // namespace implicit::filter
