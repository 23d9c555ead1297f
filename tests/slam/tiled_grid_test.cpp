// The tiled per-particle grid of grid SLAM: the inverse sensor model against a ray worked out by
// hand, cell-by-cell agreement with the dense LogOddsGrid on random scans, copy on write (copies
// share the tiles they do not write, measured), the update gate, and refused input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/slam/grid/map_update_gate.hpp"
#include "implicit/slam/grid/tiled_grid.hpp"

namespace implicit::slam {
namespace {

using robot::GridMappingOptions;
using robot::LaserMount;
using robot::LaserScan;
using robot::Pose;
using Grid = TiledLogOddsGrid;

constexpr double kTiledGridInf = std::numeric_limits<double>::infinity();

// Four beams from (1.5, 0.5) at 1 m cells: west 3.0 m (a hit), north 2.2 m (a hit), east no
// return (clears to range_max = 4 m), south below range_min (ignored).
LaserScan tiled_grid_hand_scan() {
  LaserScan scan;
  scan.angle_min = kPi;
  scan.angle_increment = -kPi / 2;
  scan.range_min = 0.1;
  scan.range_max = 4.0;
  scan.ranges = {3.0, 2.2, kTiledGridInf, 0.05};
  return scan;
}

// Every cell of [x0, x1] x [y0, y1] observed in a, with a's value, equals b's.
void expect_tiled_grids_equal(const Grid& a, const Grid& b, int x0, int y0, int x1, int y1) {
  int differ = 0;
  for (int iy = y0; iy <= y1; ++iy)
    for (int ix = x0; ix <= x1; ++ix)
      if (a.log_odds(ix, iy) != b.log_odds(ix, iy) || a.observed(ix, iy) != b.observed(ix, iy))
        ++differ;
  EXPECT_EQ(differ, 0);
}

TEST(TiledGrid, OneScanMarksTheCellsWorkedOutByHand) {
  GridMappingOptions opt;
  opt.resolution = 1.0;
  Grid grid(opt);
  grid.integrate(Pose(1.5, 0.5, 0.0), LaserMount{}, tiled_grid_hand_scan());

  const float miss = -0.4f, hit = 0.85f;
  // West: (1,0) (0,0) (-1,0) crossed, the end point 3.0 m away in (-2,0) (t in [2.5, 3.5)).
  // North: (1,0) (1,1) crossed, the end in (1,2). East: (1,0) .. (4,0) crossed, the end at
  // t = 4 in (5,0) is a miss too (no return). (1,0) is crossed by all three beams.
  EXPECT_FLOAT_EQ(grid.log_odds(1, 0), 3 * miss);
  for (int ix : {0, -1, 2, 3, 4, 5}) EXPECT_FLOAT_EQ(grid.log_odds(ix, 0), miss) << ix;
  EXPECT_FLOAT_EQ(grid.log_odds(1, 1), miss);
  EXPECT_FLOAT_EQ(grid.log_odds(-2, 0), hit);
  EXPECT_FLOAT_EQ(grid.log_odds(1, 2), hit);
  int observed = 0;
  for (int iy = -40; iy <= 40; ++iy)
    for (int ix = -40; ix <= 40; ++ix) observed += grid.observed(ix, iy);
  EXPECT_EQ(observed, 10);
  EXPECT_FALSE(grid.observed(1, -1));  // the reading below range_min
  EXPECT_EQ(grid.log_odds(1, -1), 0.0f);
  EXPECT_EQ(grid.probability(1000, -1000), 0.5);  // far outside any tile
  EXPECT_NEAR(grid.probability(-2, 0), 1.0 / (1.0 + std::exp(-0.85)), 1e-7);
  // Cells -2 and -1 are in tile -1, the others in tile 0.
  EXPECT_EQ(grid.tile_count(), 2u);
  EXPECT_EQ(grid.world_to_cell(Vec<2>(-0.01, 31.99)), Eigen::Vector2i(-1, 31));
  const Eigen::Vector2i end = grid.world_to_cell(Vec<2>(1.5 - 3.0, 0.5));  // the west beam's end
  EXPECT_EQ(end, Eigen::Vector2i(-2, 0));
  EXPECT_EQ(grid.log_odds(end), grid.log_odds(-2, 0));
  EXPECT_EQ(grid.probability(end), grid.probability(-2, 0));
  EXPECT_TRUE(grid.observed(end));

  // The dense map: x -2 .. 5, y 0 .. 2, corner at (-2, 0).
  const robot::OccupancyGrid map = grid.to_occupancy_grid();
  ASSERT_EQ(map.width(), 8);
  ASSERT_EQ(map.height(), 3);
  EXPECT_EQ(map.origin(), Vec<2>(-2.0, 0.0));
  EXPECT_EQ(map.at(0, 0), 70);  // round(100 / (1 + e^-0.85)) = round(70.06)
  EXPECT_EQ(map.at(3, 0), 23);  // round(100 / (1 + e^1.2)) = round(23.15)
  EXPECT_EQ(map.at(3, 2), 70);
  EXPECT_EQ(map.at(2, 1), robot::OccupancyGrid::kUnknown);

  // Log-odds stop at +-clamp.
  for (int k = 0; k < 20; ++k) grid.integrate(Pose(1.5, 0.5, 0.0), {}, tiled_grid_hand_scan());
  EXPECT_EQ(grid.log_odds(-2, 0), 5.0f);
  EXPECT_EQ(grid.log_odds(1, 0), -5.0f);
}

// A scan of 91 beams over half a turn at a random pose in [5, 15]^2: readings up to 4.5 m, some
// with no return, some below range_min.
LaserScan tiled_grid_random_scan(Rng& rng) {
  LaserScan scan;
  scan.angle_min = -kPi / 2;
  scan.angle_increment = kPi / 90;
  scan.range_min = 0.1;
  scan.range_max = 4.0;
  for (int i = 0; i < 91; ++i) {
    const double u = rng.uniform();
    scan.ranges.push_back(u < 0.1 ? kTiledGridInf : (u < 0.15 ? 0.05 : 4.5 * rng.uniform()));
  }
  return scan;
}

TEST(TiledGrid, EqualsTheDenseGridCellByCellOnRandomScans) {
  for (const auto& [max_range, min_echoes] : {std::pair{0.0, 0}, {3.0, 0}, {0.0, 1}, {3.0, 2}}) {
    GridMappingOptions opt;
    opt.max_range = max_range;
    opt.min_echoes = min_echoes;
    // The dense grid's origin at (0, 0) as the tiled grid's: the same arithmetic, so equal bits.
    robot::LogOddsGrid dense(400, 400, 0.05, Vec<2>::Zero(), opt);
    Grid tiled(opt);
    const LaserMount mount{0.1, 0.02, 0.05};
    Rng rng({.seed = 11, .purpose = purpose::kData});
    for (int k = 0; k < 30; ++k) {
      const double ux = rng.uniform();  // one draw per statement: a fixed order
      const double uy = rng.uniform();
      const Pose x(5.0 + 10.0 * ux, 5.0 + 10.0 * uy, 2 * kPi * rng.uniform());
      const LaserScan scan = tiled_grid_random_scan(rng);
      dense.integrate(x, mount, scan);
      tiled.integrate(x, mount, scan);
    }
    int differ = 0, observed = 0, echoed = 0;
    for (int iy = 0; iy < 400; ++iy)
      for (int ix = 0; ix < 400; ++ix) {
        differ += dense.log_odds(ix, iy) != tiled.log_odds(ix, iy) ||
                  dense.observed(ix, iy) != tiled.observed(ix, iy) ||
                  dense.echoes(ix, iy) != tiled.echoes(ix, iy);
        echoed += tiled.echoes(ix, iy) >= 2;
        observed += dense.observed(ix, iy);
      }
    EXPECT_EQ(differ, 0) << "max_range " << max_range << ", min_echoes " << min_echoes;
    EXPECT_GT(observed, 10000);
    EXPECT_GT(echoed, 10);  // the comparison includes cells with echoes of several scans
    EXPECT_FALSE(tiled.observed(-1, 200));  // nothing outside the dense grid's extent
    // The dense export over the observed box is the dense grid's, shifted.
    const robot::OccupancyGrid a = dense.to_occupancy(), b = tiled.to_occupancy_grid();
    const Eigen::Vector2i shift = a.cell_of(b.origin() + Vec<2>::Constant(0.025));
    int cells_differ = 0;
    for (int iy = 0; iy < a.height(); ++iy)
      for (int ix = 0; ix < a.width(); ++ix) {
        const int bx = ix - shift.x(), by = iy - shift.y();
        const auto v = b.contains(bx, by) ? b.at(bx, by) : robot::OccupancyGrid::kUnknown;
        cells_differ += a.at(ix, iy) != v;
      }
    EXPECT_EQ(cells_differ, 0) << "min_echoes " << min_echoes;
  }
}

// Echoes (GridMappingOptions::min_echoes): a scan counts once per cell however many of its beams
// end there, and a cell with enough echoes is fully occupied evidence for the scan match and 100
// in the map, whatever its log-odds.
TEST(TiledGrid, EchoesCountScansAndMakeACellOccupied) {
  GridMappingOptions opt;
  opt.resolution = 1.0;
  opt.min_echoes = 1;
  Grid grid(opt);
  LaserScan twice = tiled_grid_hand_scan();  // two beams west, both ending in cell (-2, 0)
  twice.angle_increment = -0.01;
  twice.ranges = {3.0, 3.2};
  grid.integrate(Pose(1.5, 0.5, 0.0), {}, twice);
  EXPECT_EQ(grid.echoes(-2, 0), 1);  // two beams of one scan: one echo
  EXPECT_FLOAT_EQ(grid.log_odds(-2, 0), 2 * 0.85f);
  EXPECT_EQ(grid.echoes(-1, 0), 0);
  EXPECT_EQ(grid.occupancy_evidence(-2, 0), 1.0);
  EXPECT_EQ(grid.occupancy_evidence(-1, 0), 0.0);   // crossed: log-odds below 0
  EXPECT_EQ(grid.occupancy_evidence(50, 50), 0.0);  // never observed, no tile

  // Clear the echo's cell with beams that cross it (from the east, ending at x = -3.5):
  // log-odds 1.7 - 5 x 0.4 = -0.3, free by log-odds alone.
  LaserScan through = tiled_grid_hand_scan();
  through.ranges = {5.0, kTiledGridInf, kTiledGridInf, 0.05};
  through.range_max = 6.0;
  for (int k = 0; k < 5; ++k) grid.integrate(Pose(1.5, 0.5, 0.0), {}, through);
  EXPECT_NEAR(grid.log_odds(-2, 0), 1.7 - 2.0, 1e-6);
  EXPECT_EQ(grid.echoes(-2, 0), 1);
  EXPECT_EQ(grid.echoes(-4, 0), 5);
  EXPECT_EQ(grid.occupancy_evidence(-2, 0), 1.0);  // the echo keeps it
  const robot::OccupancyGrid map = grid.to_occupancy_grid();
  const Eigen::Vector2i c = map.cell_of(Vec<2>(-1.5, 0.5));
  EXPECT_EQ(map.at(c.x(), c.y()), 100);

  opt.min_echoes = 2;  // the same scans, two echoes needed: log-odds decide (-2, 0)
  Grid two(opt);
  two.integrate(Pose(1.5, 0.5, 0.0), {}, twice);
  for (int k = 0; k < 5; ++k) two.integrate(Pose(1.5, 0.5, 0.0), {}, through);
  EXPECT_EQ(two.occupancy_evidence(-2, 0), 0.0);
  EXPECT_EQ(two.occupancy_evidence(-4, 0), 1.0);  // five echoes
  opt.min_echoes = 0;                             // log-odds alone: the end cell's tanh(l / 2)
  Grid none(opt);
  none.integrate(Pose(1.5, 0.5, 0.0), {}, twice);
  EXPECT_DOUBLE_EQ(none.occupancy_evidence(-2, 0), std::tanh(0.5 * double(2 * 0.85f)));
  EXPECT_EQ(none.echoes(-2, 0), 1);  // counted, not used
}

TEST(TiledGrid, ACopySharesTheTilesItDoesNotWrite) {
  GridMappingOptions opt;
  Grid parent(opt);
  Rng rng({.seed = 12, .purpose = purpose::kData});
  std::vector<Pose> poses;
  std::vector<LaserScan> scans;
  for (int k = 0; k < 8; ++k) {       // spread over 10 m x 10 m: a few dozen tiles of 1.6 m
    const double ux = rng.uniform();  // one draw per statement: a fixed order
    const double uy = rng.uniform();
    poses.emplace_back(5.0 + 10.0 * ux, 5.0 + 10.0 * uy, 6 * rng.uniform());
    scans.push_back(tiled_grid_random_scan(rng));
    parent.integrate(poses.back(), {}, scans.back());
  }
  const std::size_t tiles = parent.tile_count();
  ASSERT_GT(tiles, 20u);
  EXPECT_EQ(parent.unique_tile_count(), tiles);

  Grid child = parent;  // resampling
  EXPECT_EQ(child.tile_count(), tiles);
  EXPECT_EQ(child.unique_tile_count(), 0u);
  EXPECT_EQ(parent.unique_tile_count(), 0u);
  EXPECT_EQ(child.bytes().shared, tiles * sizeof(Grid::Tile));

  // Scan 3 again, cut to 1 m: its cells lie on the parent's beams, so in the parent's tiles. The
  // tiles it touches, counted on a grid of its own, are the ones the child copies.
  LaserScan small = scans[3];
  for (double& r : small.ranges) r = std::min(r, 1.0);
  const Pose at = poses[3];
  Grid alone(opt);
  alone.integrate(at, {}, small);
  const std::size_t touched = alone.tile_count();
  ASSERT_GE(touched, 1u);
  ASSERT_LT(touched, tiles);

  child.integrate(at, {}, small);
  EXPECT_EQ(child.tile_count(), tiles);
  EXPECT_EQ(child.unique_tile_count(), touched);
  EXPECT_EQ(parent.unique_tile_count(), touched);  // the old copies now belong to parent alone
  const TiledGridBytes b = child.bytes();
  EXPECT_EQ(b.tiles, tiles);
  EXPECT_EQ(b.unique_tiles, touched);
  EXPECT_EQ(b.shared, (tiles - touched) * sizeof(Grid::Tile));
  EXPECT_EQ(b.owned, b.index + touched * sizeof(Grid::Tile));
  {
    const Grid both[] = {parent, child};  // copies: the same tiles, each counted once
    EXPECT_EQ(Grid::distinct_tiles(both), tiles + touched);
  }

  // The parent is what it was: the same as a grid given only its scans; the child as one given
  // the extra scan too.
  Grid replay(opt);
  for (std::size_t k = 0; k < scans.size(); ++k) replay.integrate(poses[k], {}, scans[k]);
  expect_tiled_grids_equal(parent, replay, 0, 0, 400, 400);
  replay.integrate(at, {}, small);
  expect_tiled_grids_equal(child, replay, 0, 0, 400, 400);
  int changed = 0;
  for (int iy = 0; iy <= 400; ++iy)
    for (int ix = 0; ix <= 400; ++ix) changed += parent.log_odds(ix, iy) != child.log_odds(ix, iy);
  EXPECT_GT(changed, 0);

  // Once the parent is gone, every tile of the child is its own.
  { const Grid gone = std::move(parent); }
  EXPECT_EQ(child.unique_tile_count(), tiles);
}

TEST(TiledGrid, CopiesWrittenOnOtherThreadsLeaveEachOtherAlone) {
  Grid parent;
  Rng rng({.seed = 13, .purpose = purpose::kData});
  const Pose at(10.0, 10.0, 0.0);
  const LaserScan first = tiled_grid_random_scan(rng);
  parent.integrate(at, {}, first);
  // Four children over the same tiles, each given its own scan on its own thread.
  std::vector<LaserScan> scans;
  for (int j = 0; j < 4; ++j) scans.push_back(tiled_grid_random_scan(rng));
  std::vector<Grid> children(4, parent);
  {
    std::vector<std::jthread> threads;
    for (std::size_t j = 0; j < 4; ++j)
      threads.emplace_back([&, j] { children[j].integrate(at, {}, scans[j]); });
  }
  for (std::size_t j = 0; j < 4; ++j) {
    Grid replay = parent;
    replay.integrate(at, {}, scans[j]);
    expect_tiled_grids_equal(children[j], replay, 100, 100, 300, 300);
  }
  Grid alone;
  alone.integrate(at, {}, first);
  expect_tiled_grids_equal(parent, alone, 100, 100, 300, 300);  // the parent is unchanged
}

TEST(TiledGrid, MapUpdateGateFollowsGmappingThresholds) {
  const MapUpdateGate gate;  // 1 m, 0.5 rad
  const Pose last(2.0, 3.0, 3.1);
  EXPECT_FALSE(gate.due(last, last));
  EXPECT_FALSE(gate.due(last, Pose(2.0, 3.99, 3.1)));
  EXPECT_TRUE(gate.due(last, Pose(2.0, 4.0, 3.1)));    // 1 m
  EXPECT_FALSE(gate.due(last, Pose(2.0, 3.0, -3.1)));  // 0.083 rad across +-pi
  EXPECT_TRUE(gate.due(last, Pose(2.0, 3.0, 3.7)));
  EXPECT_TRUE(gate.due(last, Pose(2.0, 3.0, 2.5)));
  const MapUpdateGate every{0.0, 0.0};  // zero thresholds: every scan
  EXPECT_TRUE(every.due(last, last));
}

// The message of the InvalidArgument that f throws ("" when it throws none).
template <class F>
std::string tiled_grid_error(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(TiledGrid, RefusesBadInputNamingIt) {
  const auto has = [](const std::string& message, const char* part) {
    return message.find(part) != std::string::npos;
  };
  GridMappingOptions bad;
  bad.resolution = -0.05;
  EXPECT_TRUE(has(tiled_grid_error([&] { Grid g(bad); }), "resolution"));
  bad = {};
  bad.log_odds_miss = 0.4;
  EXPECT_TRUE(has(tiled_grid_error([&] { Grid g(bad); }), "log_odds_miss"));

  Grid grid;
  const LaserScan scan = tiled_grid_hand_scan();
  grid.integrate(Pose(1.0, 1.0, 0.0), {}, scan);
  const robot::OccupancyGrid before = grid.to_occupancy_grid();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.integrate(Pose(nan, 0, 0), {}, scan); }),
                  "expected a finite pose"));
  EXPECT_TRUE(has(tiled_grid_error([&] {
                    grid.integrate(Pose::Zero(), {0, nan, 0}, scan);
                  }),
                  "finite laser mount"));
  LaserScan broken = scan;
  broken.ranges[2] = nan;
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.integrate(Pose::Zero(), {}, broken); }),
                  "beam 2 has range nan"));
  broken.ranges.clear();
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.integrate(Pose::Zero(), {}, broken); }),
                  "at least one beam"));
  // Too far from the origin for the cell indices, and too large an area for the index: refused
  // before any cell changes.
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.integrate(Pose(1e8, 0, 0), {}, scan); }),
                  "expected beams within"));
  LaserScan wide = scan;
  wide.range_max = 1e5;  // a no-return beam clears 100 km
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.integrate(Pose::Zero(), {}, wide); }),
                  "expected a map of at most 1048576 tiles"));
  EXPECT_TRUE(has(tiled_grid_error([&] { grid.world_to_cell(Vec<2>(0.0, nan)); }),
                  "expected a finite point"));
  const robot::OccupancyGrid after = grid.to_occupancy_grid();
  EXPECT_EQ(after.width(), before.width());
  EXPECT_TRUE(std::equal(after.data().begin(), after.data().end(), before.data().begin()));
  EXPECT_TRUE(Grid().to_occupancy_grid().empty());

  EXPECT_TRUE(has(tiled_grid_error([&] { MapUpdateGate{nan, 0.5}.validate(); }), "linear_update"));
  EXPECT_TRUE(has(tiled_grid_error([] { MapUpdateGate{1.0, -0.1}.validate(); }), "angular_update"));
  EXPECT_TRUE(has(tiled_grid_error([&] { MapUpdateGate{}.due(Pose(0, nan, 0), Pose::Zero()); }),
                  "last_update"));
}

}  // namespace
}  // namespace implicit::slam
