// The absolute trajectory error of grid SLAM runs (spec §3.13.4) against an independent
// computation: the closed-form least-squares rotation and translation in the plane (the angle
// from the summed cross and dot products of the centred positions), and its defining property,
// that no rigid motion, the identity included, leaves a smaller RMSE.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "implicit/robot/carmen.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"

namespace implicit::slam {
namespace {

const robot::CarmenLog& ate_log() {
  static const robot::CarmenLog log =
      robot::read_carmen(std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz");
  return log;
}

/// The RMSE of est's positions after rotating by `angle` and translating by (tx, ty).
double rmse_after(const std::vector<robot::Pose>& est, const std::vector<GridSlamPose>& ref,
                  double angle, double tx, double ty) {
  double ss = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double x = std::cos(angle) * est[i](0) - std::sin(angle) * est[i](1) + tx;
    const double y = std::sin(angle) * est[i](0) + std::cos(angle) * est[i](1) + ty;
    ss += std::pow(x - ref[i].pose(0), 2) + std::pow(y - ref[i].pose(1), 2);
  }
  return std::sqrt(ss / static_cast<double>(est.size()));
}

/// The least-squares alignment in the plane, written out: returns the RMSE after it.
double closed_form_ate(const std::vector<robot::Pose>& est, const std::vector<GridSlamPose>& ref,
                       double* angle_out = nullptr) {
  const double n = static_cast<double>(est.size());
  double ex = 0, ey = 0, rx = 0, ry = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    ex += est[i](0) / n;
    ey += est[i](1) / n;
    rx += ref[i].pose(0) / n;
    ry += ref[i].pose(1) / n;
  }
  double cross = 0, dot = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double ax = est[i](0) - ex, ay = est[i](1) - ey;
    const double bx = ref[i].pose(0) - rx, by = ref[i].pose(1) - ry;
    cross += ax * by - ay * bx;
    dot += ax * bx + ay * by;
  }
  const double angle = std::atan2(cross, dot);
  if (angle_out) *angle_out = angle;
  const double tx = rx - (std::cos(angle) * ex - std::sin(angle) * ey);
  const double ty = ry - (std::sin(angle) * ex + std::cos(angle) * ey);
  return rmse_after(est, ref, angle, tx, ty);
}

TEST(GridSlamAte, IsTheClosedFormPlanarAlignmentsRmse) {
  GridSlamRunOptions o;
  o.filter.particles = 3;
  o.max_scans = 60;
  const GridSlamRun run = run_grid_slam(ate_log(), o);
  ASSERT_GT(run.trajectory.size(), 10u);
  ASSERT_TRUE(run.ate_m.has_value());
  ASSERT_TRUE(run.odometry_ate_m.has_value());
  std::vector<robot::Pose> est;
  for (const auto& p : run.trajectory) est.push_back(p.pose);
  double angle = 0.0;
  const double expected = closed_form_ate(est, run.reference, &angle);
  // Two computations of the same sums in a different order: agreement to rounding.
  EXPECT_NEAR(*run.ate_m, expected, 1e-9 * (1.0 + expected));
  // The minimum: the identity does no better.
  EXPECT_LE(*run.ate_m, rmse_after(est, run.reference, 0.0, 0.0, 0.0) + 1e-12);
  EXPECT_GT(*run.ate_m, 0.0);
  EXPECT_GT(*run.odometry_ate_m, 0.0);
}

TEST(GridSlamAte, OneScanHasNoAlignmentAndSaysSo) {
  GridSlamRunOptions o;
  o.filter.particles = 2;
  o.max_scans = 1;
  const GridSlamRun run = run_grid_slam(ate_log(), o);
  EXPECT_EQ(run.processed, 1u);
  EXPECT_FALSE(run.ate_m.has_value());
  EXPECT_FALSE(run.odometry_ate_m.has_value());
}

}  // namespace
}  // namespace implicit::slam
