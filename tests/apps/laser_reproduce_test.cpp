// The laser_mcl experiment of `implicit reproduce` (experiments/laser_reproduce.hpp) on the
// bundled ACES log: the dataset cache returns what a direct load returns and loads once per
// options; the figure's files agree with the run they come from (the track's errors are the
// distances to the reference, their RMSE the result's); the global starts' count is the runs'.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "experiments/laser_reproduce.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::experiments {
namespace {

using test::TempDir;

const std::filesystem::path kAces =
    std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data/carmen/aces-corrected.log.gz";

LaserDataOptions aces(std::size_t updates) {
  LaserDataOptions o;
  o.data = kAces;
  o.max_updates = updates;
  return o;
}

// Each test uses its own max_updates, so that the cache of one does not serve another when the
// program runs them all in one process.
TEST(LaserReproduce, TheCacheLoadsOncePerOptionsAndReturnsWhatALoadReturns) {
  const CachedDataset first = cached_laser_dataset(aces(15));
  const CachedDataset again = cached_laser_dataset(aces(15));
  EXPECT_FALSE(first.from_cache);
  EXPECT_TRUE(again.from_cache);
  EXPECT_EQ(first.data.get(), again.data.get());
  EXPECT_GT(first.load_seconds, 0.0);
  EXPECT_EQ(again.load_seconds, first.load_seconds);

  const LaserDataset direct = load_laser_dataset(aces(15));
  const LaserDataset& cached = *first.data;
  ASSERT_EQ(cached.reference.size(), 15u);
  ASSERT_EQ(cached.reference.size(), direct.reference.size());
  for (std::size_t k = 0; k < direct.reference.size(); ++k) {
    EXPECT_EQ(cached.reference[k], direct.reference[k]) << k;
    EXPECT_EQ(cached.scans[k].ranges, direct.scans[k].ranges) << k;
  }
  EXPECT_TRUE(std::equal(cached.map.data().begin(), cached.map.data().end(),
                         direct.map.data().begin(), direct.map.data().end()));

  // Other options are another dataset.
  const CachedDataset other = cached_laser_dataset(aces(16));
  EXPECT_FALSE(other.from_cache);
  EXPECT_EQ(other.data->reference.size(), 16u);
}

TEST(LaserReproduce, TheFigureFilesAreTheRunsTrackAndTheReference) {
  TempDir dir("laser_reproduce_figure");
  LaserMclSettings s;
  s.data = aces(12);
  s.proposal = ProposalKind::kImplicit;
  s.particles = 20;
  s.runs = 2;
  const nlohmann::json j = run_laser_reproduce(s, dir.path());
  EXPECT_EQ(j["figure_files"].size(), 3u);
  EXPECT_EQ(j["runs"], 2);
  EXPECT_EQ(j["updates"], 12);

  const auto ref = robot::read_numeric_csv(dir.path() / "laser_mcl_reference.csv",
                                           {"update", "time_s", "x_m", "y_m", "heading_rad"});
  const auto track = robot::read_numeric_csv(
      dir.path() / "laser_mcl_track_implicit.csv",
      {"update", "time_s", "x_m", "y_m", "heading_rad", "error_m", "particles"});
  const LaserDataset& d = *cached_laser_dataset(aces(12)).data;
  ASSERT_EQ(ref.rows, 12u);
  ASSERT_EQ(track.rows, 12u);
  double sum_squares = 0.0;
  for (std::size_t k = 0; k < 12; ++k) {
    // Written with 4 decimals: each coordinate is within 5e-5 m of the pose.
    EXPECT_NEAR(ref.at(k, 2), d.reference[k](0), 5e-5);
    EXPECT_NEAR(ref.at(k, 3), d.reference[k](1), 5e-5);
    EXPECT_NEAR(ref.at(k, 1), d.scans[k].time - d.scans[0].time, 5e-4);
    EXPECT_EQ(track.at(k, 1), ref.at(k, 1));
    EXPECT_EQ(track.at(k, 6), 20.0);
    // The error is the distance from the estimate to the reference: from the rounded
    // coordinates, to within the rounding of the four of them (2 · 5e-5 · √2) and of the error
    // itself (6 significant digits).
    const double e = std::hypot(track.at(k, 2) - ref.at(k, 2), track.at(k, 3) - ref.at(k, 3));
    EXPECT_NEAR(track.at(k, 5), e, 1.5e-4 + 1e-5 * e) << k;
    sum_squares += track.at(k, 5) * track.at(k, 5);
  }
  // The figure shows the first run: its RMSE over the updates is that run's in the result.
  const double rmse = std::sqrt(sum_squares / 12.0);
  EXPECT_NEAR(j["per_run"][0]["position_rmse_m"].get<double>(), rmse, 1e-5 * rmse + 1e-9);

  const auto map =
      robot::read_numeric_csv(dir.path() / "laser_mcl_map.csv", {"x_m", "y_m", "resolution_m"});
  std::size_t occupied = 0;
  for (int iy = 0; iy < d.map.height(); ++iy)
    for (int ix = 0; ix < d.map.width(); ++ix) occupied += d.map.is_occupied(ix, iy) ? 1 : 0;
  ASSERT_EQ(map.rows, occupied);
  for (std::size_t i = 0; i < map.rows; i += 97) {
    const Eigen::Vector2i c = d.map.cell_of(Vec<2>(map.at(i, 0), map.at(i, 1)));
    EXPECT_TRUE(d.map.is_occupied(c(0), c(1))) << "row " << i;
    EXPECT_EQ(map.at(i, 2), d.map.resolution());
  }

  // Writing the figure changes no result: the same run without it.
  const nlohmann::json plain = run_laser_reproduce(s, {});
  EXPECT_TRUE(plain["figure_files"].empty());
  EXPECT_EQ(plain["position_rmse_m"], j["position_rmse_m"]);
  EXPECT_EQ(plain["per_run"][1]["final_error_m"], j["per_run"][1]["final_error_m"]);
}

TEST(LaserReproduce, GlobalStartsCountTheirSuccesses) {
  LaserMclSettings s;
  s.data = aces(24);
  s.proposal = ProposalKind::kBootstrap;
  s.particles = 300;
  s.runs = 3;
  s.start = StartKind::kGlobal;
  const nlohmann::json j = run_laser_reproduce(s, {});
  int successes = 0;
  for (const auto& run : j["per_run"]) successes += run["global_success"].get<bool>() ? 1 : 0;
  EXPECT_EQ(j["global_successes"], successes);
  EXPECT_NEAR(j["global_success_rate"].get<double>(), successes / 3.0, 1e-12);
  if (successes == 0) {
    EXPECT_TRUE(j["updates_to_converge_median"].is_null());
  } else {
    EXPECT_TRUE(j["updates_to_converge_median"].is_number());
  }
}

TEST(LaserReproduce, AFigureFolderThatIsAFileIsAnErrorNamingIt) {
  TempDir dir("laser_reproduce_bad_folder");
  const auto file = dir.path() / "taken";
  test::write_file(file, "x");
  LaserMclSettings s;
  s.data = aces(12);
  s.particles = 10;
  s.runs = 1;
  try {
    run_laser_reproduce(s, file);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace implicit::experiments
