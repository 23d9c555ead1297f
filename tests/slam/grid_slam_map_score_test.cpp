// The map score of grid SLAM runs (spec §3.13.5): on one processed scan the filter's map is the
// reference map cell by cell (both map scan 0 at the first reference pose), so every score is 1;
// longer runs give fractions in [0, 1]; the score can be skipped; bad options are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/map_comparison.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"

namespace implicit::slam {
namespace {

const robot::CarmenLog& aces() {
  static const robot::CarmenLog log =
      robot::read_carmen(std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz");
  return log;
}

GridSlamRunOptions few_particles(std::size_t max_scans) {
  GridSlamRunOptions o;
  o.filter.particles = 3;
  o.max_scans = max_scans;
  return o;
}

void expect_all_ones(const robot::MapComparison& s, const char* which) {
  EXPECT_GT(s.known_in_both, 0u) << which;
  EXPECT_GT(s.reference_occupied, 0u) << which;
  EXPECT_EQ(s.estimate_occupied, s.reference_occupied) << which;
  EXPECT_EQ(s.agreement, 1.0) << which;
  EXPECT_EQ(s.occupied_precision, 1.0) << which;
  EXPECT_EQ(s.occupied_recall, 1.0) << which;
  EXPECT_EQ(s.occupied_f1, 1.0) << which;
}

TEST(GridSlamMapScore, OneScanMapsAreTheReferenceMapCellByCell) {
  const GridSlamRun run = run_grid_slam(aces(), few_particles(1));
  ASSERT_EQ(run.processed, 1u);
  ASSERT_TRUE(run.map_score && run.odometry_map_score);
  // The filter's map, the dead-reckoning map (odometry starts at the reference pose) and the
  // reference map all hold scan 0 seen from the first reference pose, with the same inverse
  // sensor model on the same lattice: identical known cells.
  const robot::OccupancyGrid truth =
      robot::build_map(std::vector<robot::Pose>{aces().laser_poses[0]},
                       std::vector<robot::LaserScan>{aces().scans[0]},
                       GridSlamRunOptions{}.filter.mount, GridSlamRunOptions{}.filter.map);
  std::size_t known = 0;
  for (int iy = 0; iy < truth.height(); ++iy)
    for (int ix = 0; ix < truth.width(); ++ix) {
      if (truth.at(ix, iy) == robot::OccupancyGrid::kUnknown) continue;
      ++known;
      const Eigen::Vector2i c = run.map.cell_of(truth.cell_center(ix, iy));
      ASSERT_TRUE(run.map.contains(c.x(), c.y())) << ix << ", " << iy;
      ASSERT_EQ(run.map.at(c.x(), c.y()), truth.at(ix, iy)) << ix << ", " << iy;
    }
  std::size_t filter_known = 0;
  for (std::int8_t v : run.map.data()) filter_known += v != robot::OccupancyGrid::kUnknown;
  EXPECT_EQ(filter_known, known);
  expect_all_ones(*run.map_score, "filter");
  expect_all_ones(*run.odometry_map_score, "dead reckoning");
  EXPECT_EQ(run.map_score->tolerance_m, 0.05);  // one cell
  EXPECT_GE(run.map_score_cpu_seconds, run.reference_map_cpu_seconds);
}

TEST(GridSlamMapScore, LongerRunsScoreFractionsAndTheScoreCanBeSkipped) {
  const GridSlamRun run = run_grid_slam(aces(), few_particles(60));
  ASSERT_GT(run.processed, 2u);
  for (const auto* s : {&*run.map_score, &*run.odometry_map_score}) {
    ASSERT_TRUE(s->agreement && s->occupied_precision && s->occupied_recall && s->occupied_f1);
    for (double v : {*s->agreement, *s->occupied_precision, *s->occupied_recall, *s->occupied_f1}) {
      EXPECT_GE(v, 0.0);
      EXPECT_LE(v, 1.0);
    }
  }
  GridSlamRunOptions skip = few_particles(60);
  skip.score_map = false;
  const GridSlamRun bare = run_grid_slam(aces(), skip);
  EXPECT_FALSE(bare.map_score.has_value());
  EXPECT_FALSE(bare.odometry_map_score.has_value());
  EXPECT_EQ(bare.map_score_cpu_seconds, 0.0);
  // The score reads the run, never changes it.
  EXPECT_EQ(bare.relations.translation_mean, run.relations.translation_mean);
  // A tolerance of zero: only coinciding cells match, never more than at one cell.
  GridSlamRunOptions exact = few_particles(60);
  exact.map_comparison.tolerance_m = 0.0;
  const GridSlamRun strict = run_grid_slam(aces(), exact);
  EXPECT_LE(*strict.map_score->occupied_precision, *run.map_score->occupied_precision);
  EXPECT_EQ(strict.map_score->agreement, run.map_score->agreement);
}

TEST(GridSlamMapScore, RefusesABadTolerance) {
  GridSlamRunOptions o = few_particles(1);
  o.map_comparison.tolerance_m = -0.05;
  try {
    run_grid_slam(aces(), o);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("tolerance_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace implicit::slam
