// Grid SLAM with recorded odometry (GridOdometrySource::kRecorded, a ROS bag's): the filter is
// given the log's own poses at the gated scans, unperturbed, and the run has no reference, so the
// scores that need one are absent (empty relations, no ATE, no map score), never zeros.
#include <gtest/gtest.h>

#include <string>

#include "implicit/robot/carmen.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"

namespace implicit::slam {
namespace {

TEST(GridSlamRecorded, UsesTheLogsPosesAsOdometryAndScoresNothing) {
  const robot::CarmenLog log =
      robot::read_carmen(std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz");
  GridSlamRunOptions o;
  o.filter.particles = 3;
  o.max_scans = 40;
  o.proposal = GridProposalKind::kBootstrap;
  o.odometry = GridOdometrySource::kRecorded;
  const GridSlamRun run = run_grid_slam(log, o);
  ASSERT_GT(run.processed, 2u);
  EXPECT_FALSE(run.has_reference);
  EXPECT_TRUE(run.reference.empty());
  EXPECT_TRUE(run.relations.translation.empty());
  EXPECT_TRUE(run.odometry_relations.translation.empty());
  EXPECT_FALSE(run.ate_m.has_value());
  EXPECT_FALSE(run.odometry_ate_m.has_value());
  EXPECT_FALSE(run.map_score.has_value());
  EXPECT_FALSE(run.odometry_map_score.has_value());
  ASSERT_EQ(run.trajectory.size(), run.processed);
  ASSERT_EQ(run.odometry.size(), run.processed);
  // Each odometry pose is the log's pose at its scan, bit for bit (matched by the scan's time:
  // the first 40 ACES scans have increasing times).
  for (std::size_t i = 0; i < run.processed; ++i) {
    std::size_t k = 0;
    while (k < log.scans.size() && log.scans[k].time != run.trajectory[i].time) ++k;
    ASSERT_LT(k, log.scans.size()) << "processed scan " << i;
    EXPECT_EQ(run.odometry[i], log.laser_poses[k]) << "processed scan " << i;
  }
  // The synthesised run gates the same scans (the gate reads the same poses) but perturbs them.
  o.odometry = GridOdometrySource::kSynthesised;
  const GridSlamRun synthesised = run_grid_slam(log, o);
  EXPECT_TRUE(synthesised.has_reference);
  ASSERT_EQ(synthesised.processed, run.processed);
  EXPECT_NE(synthesised.odometry.back(), run.odometry.back());
  EXPECT_TRUE(synthesised.ate_m.has_value());
}

}  // namespace
}  // namespace implicit::slam
