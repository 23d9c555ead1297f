// Occupancy mapping with known poses: single beams whose cells are worked out by hand, the
// clamp, the options and inputs refused, and a square room mapped from simulated scans.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/grid_mapping.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

LaserScan one_beam(double bearing, double range, double range_max = 8.0) {
  LaserScan s;
  s.angle_min = bearing;
  s.angle_increment = 0.01;
  s.range_min = 0.1;
  s.range_max = range_max;
  s.ranges = {range};
  return s;
}

// round(100 p) for log-odds l: what to_occupancy makes of one cell.
int percent(double l) { return static_cast<int>(std::lround(100.0 * (1 - 1 / (1 + std::exp(l))))); }

TEST(GridMapping, OneBeamMissesTheCellsItCrossesAndHitsItsEndCell) {
  const GridMappingOptions opt;
  // Resolution 1, from the centre of cell (0, 1) eastwards, 3.2 m: the end point x = 3.7 is in
  // cell (3, 1); cells (0..2, 1) are crossed.
  LogOddsGrid g(10, 3, 1.0, Vec<2>::Zero(), opt);
  g.integrate(Pose(0.5, 1.5, 0.0), LaserMount{}, one_beam(0.0, 3.2));
  for (int ix = 0; ix < 10; ++ix)
    for (int iy = 0; iy < 3; ++iy) {
      const bool crossed = iy == 1 && ix < 3, end = iy == 1 && ix == 3;
      EXPECT_EQ(g.observed(ix, iy), crossed || end) << ix << ", " << iy;
      EXPECT_EQ(g.log_odds(ix, iy), crossed ? float(opt.log_odds_miss)
                                    : end   ? float(opt.log_odds_hit)
                                            : 0.0f);
    }
  const OccupancyGrid map = g.to_occupancy();
  EXPECT_EQ(map.at(1, 1), percent(-0.4));  // 40
  EXPECT_EQ(map.at(3, 1), percent(0.85));  // 70
  EXPECT_EQ(map.at(4, 1), OccupancyGrid::kUnknown);
  EXPECT_EQ(map.at(1, 0), OccupancyGrid::kUnknown);
  EXPECT_EQ(percent(-0.4), 40);
  EXPECT_EQ(percent(0.85), 70);
}

TEST(GridMapping, DiagonalBeamFromAMountedSensor) {
  // The robot at (0.5, 0.3) facing +y, the laser 0.2 m ahead of it turned back by 90 degrees:
  // the sensor is at (0.5, 0.5) facing +x. Along (2, 1)/sqrt(5) the beam is at (0.5 + 2s,
  // 0.5 + s) after sqrt(5) s and crosses x = 1, y = 1, x = 2, x = 3 at s = 0.25, 0.5, 0.75,
  // 1.25: cells (0,0) (1,0) (1,1) (2,1), then (3,1), where it ends at s = 1.4.
  LogOddsGrid g(6, 6, 1.0, Vec<2>::Zero());
  g.integrate(Pose(0.5, 0.3, kPi / 2), LaserMount{0.2, 0.0, -kPi / 2},
              one_beam(std::atan2(1.0, 2.0), 1.4 * std::sqrt(5.0)));
  const int misses[][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 1}};
  int observed = 0;
  for (int ix = 0; ix < 6; ++ix)
    for (int iy = 0; iy < 6; ++iy) observed += g.observed(ix, iy) ? 1 : 0;
  EXPECT_EQ(observed, 5);
  for (const auto& m : misses) EXPECT_EQ(g.log_odds(m[0], m[1]), -0.4f) << m[0] << ", " << m[1];
  EXPECT_EQ(g.log_odds(3, 1), 0.85f);
}

TEST(GridMapping, NoReturnBeamsClearUpToTheirRangeAndShortReadingsAreIgnored) {
  // No return (+inf): misses up to range_max 8, the end point x = 8.5 in cell 8 included.
  LogOddsGrid g(10, 1, 1.0, Vec<2>::Zero());
  g.integrate(Pose(0.5, 0.5, 0.0), LaserMount{}, one_beam(0.0, INFINITY));
  for (int ix = 0; ix < 10; ++ix) EXPECT_EQ(g.log_odds(ix, 0), ix <= 8 ? -0.4f : 0.0f) << ix;
  // A reading at range_max is no return too; below range_min it is no measurement.
  LogOddsGrid h(10, 1, 1.0, Vec<2>::Zero());
  h.integrate(Pose(0.5, 0.5, 0.0), LaserMount{}, one_beam(0.0, 3.0, 3.0));
  for (int ix = 0; ix < 10; ++ix) EXPECT_EQ(h.log_odds(ix, 0), ix <= 3 ? -0.4f : 0.0f) << ix;
  LogOddsGrid none(10, 1, 1.0, Vec<2>::Zero());
  none.integrate(Pose(0.5, 0.5, 0.0), LaserMount{}, one_beam(0.0, 0.05));
  EXPECT_FALSE(none.observed(0, 0));
  // With max_range 4, a wall 5 m away only clears up to 4 m (x = 4.5, cell 4).
  GridMappingOptions opt;
  opt.max_range = 4.0;
  LogOddsGrid k(10, 1, 1.0, Vec<2>::Zero(), opt);
  k.integrate(Pose(0.5, 0.5, 0.0), LaserMount{}, one_beam(0.0, 5.0));
  for (int ix = 0; ix < 10; ++ix) EXPECT_EQ(k.log_odds(ix, 0), ix <= 4 ? -0.4f : 0.0f) << ix;
  // A max_range beyond range_max does not clear beyond range_max.
  opt.max_range = 9.5;
  LogOddsGrid m(10, 1, 1.0, Vec<2>::Zero(), opt);
  m.integrate(Pose(0.5, 0.5, 0.0), LaserMount{}, one_beam(0.0, INFINITY, 3.0));
  for (int ix = 0; ix < 10; ++ix) EXPECT_EQ(m.log_odds(ix, 0), ix <= 3 ? -0.4f : 0.0f) << ix;
}

TEST(GridMapping, BeamsOutsideTheExtentAndTheClamp) {
  // The sensor 3 m west of the grid: the beam enters at x = 0 and ends in cell 2 (x = 2.5).
  // Echoes off: the map shows the log-odds.
  GridMappingOptions log_odds_only;
  log_odds_only.min_echoes = 0;
  LogOddsGrid g(5, 1, 1.0, Vec<2>::Zero(), log_odds_only);
  g.integrate(Pose(-3.0, 0.5, 0.0), LaserMount{}, one_beam(0.0, 5.5));
  EXPECT_EQ(g.log_odds(0, 0), -0.4f);
  EXPECT_EQ(g.log_odds(1, 0), -0.4f);
  EXPECT_EQ(g.log_odds(2, 0), 0.85f);
  EXPECT_FALSE(g.observed(3, 0));
  // Twenty times the same beam: +17 and -8 are clamped to +-5.
  for (int k = 0; k < 19; ++k) g.integrate(Pose(-3.0, 0.5, 0.0), LaserMount{}, one_beam(0.0, 5.5));
  EXPECT_EQ(g.log_odds(2, 0), 5.0f);
  EXPECT_EQ(g.log_odds(0, 0), -5.0f);
  EXPECT_EQ(g.to_occupancy().at(2, 0), percent(5.0));  // 99
  EXPECT_EQ(g.echoes(2, 0), 20);
  // A beam that passes beside the grid changes nothing.
  LogOddsGrid h(5, 1, 1.0, Vec<2>::Zero());
  h.integrate(Pose(-3.0, 5.0, 0.0), LaserMount{}, one_beam(0.0, INFINITY));
  for (int ix = 0; ix < 5; ++ix) EXPECT_FALSE(h.observed(ix, 0));
}

// A wall cell seen edge-on: scan A's beam ends in cell 3 (a hit), scan B's beams cross it on
// their way further. Log-odds alone let the crossings erase it; echoes from two scans keep it.
TEST(GridMapping, EchoesFromTwoScansKeepACellTheBeamsCrossingItWouldClear) {
  const Pose at(0.5, 0.5, 0.0);
  LaserScan b = one_beam(0.0, 6.2);  // ends in cell 6, crossing cells 0..5
  b.ranges = {6.2, 6.2, 6.2};        // three beams a micro-radian apart: three crossings of cell 3
  b.angle_increment = 1e-6;
  const auto map_after = [&](int min_echoes, int hits, int crossings) {
    GridMappingOptions opt;
    opt.min_echoes = min_echoes;
    LogOddsGrid g(8, 1, 1.0, Vec<2>::Zero(), opt);
    for (int k = 0; k < hits; ++k) g.integrate(at, LaserMount{}, one_beam(0.0, 3.2));
    for (int k = 0; k < crossings; ++k) g.integrate(at, LaserMount{}, b);
    return std::pair(g.to_occupancy().at(3, 0), g.echoes(3, 0));
  };
  // Two hits (+1.7), then two scans crossing it three times each (-2.4): log-odds -0.7.
  EXPECT_EQ(map_after(0, 2, 2), std::pair(static_cast<std::int8_t>(percent(1.7 - 2.4)), 2));
  EXPECT_EQ(map_after(2, 2, 2), std::pair(OccupancyGrid::kOccupied, 2));
  // One scan's echo is not enough, however often it is crossed.
  EXPECT_EQ(map_after(2, 1, 2).first, percent(0.85 - 2.4));
  // An echo counts once per scan: three beams of one scan ending in one cell are one echo.
  LogOddsGrid g(8, 1, 1.0, Vec<2>::Zero());
  g.integrate(at, LaserMount{}, b);
  EXPECT_EQ(g.echoes(6, 0), 1);
  EXPECT_FLOAT_EQ(g.log_odds(6, 0), 3 * 0.85f);
  EXPECT_EQ(g.echoes(3, 0), 0);
  // No return is no echo.
  g.integrate(at, LaserMount{}, one_beam(0.0, INFINITY));
  EXPECT_EQ(g.echoes(7, 0), 0);
}

std::string mapping_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(GridMapping, RefusesBadOptionsPosesAndScans) {
  auto with = [](const std::function<void(GridMappingOptions&)>& change) {
    GridMappingOptions o;
    change(o);
    return mapping_error([&] { o.validate(); });
  };
  EXPECT_THAT(with([](auto& o) { o.resolution = 0; }), HasSubstr("expected resolution > 0"));
  EXPECT_THAT(with([](auto& o) { o.log_odds_hit = -1; }), HasSubstr("expected log_odds_hit > 0"));
  EXPECT_THAT(with([](auto& o) { o.log_odds_miss = 0.4; }),
              HasSubstr("expected log_odds_miss < 0, got 0.4"));
  EXPECT_THAT(with([](auto& o) { o.clamp = std::nan(""); }), HasSubstr("expected clamp > 0"));
  EXPECT_THAT(with([](auto& o) { o.max_range = -1; }), HasSubstr("expected max_range >= 0"));
  EXPECT_THAT(with([](auto& o) { o.margin = INFINITY; }), HasSubstr("expected margin >= 0"));
  EXPECT_THAT(with([](auto& o) { o.min_echoes = -1; }),
              HasSubstr("expected min_echoes in [0, 255] (0: off), got -1"));
  EXPECT_THAT(with([](auto& o) { o.min_echoes = 256; }),
              HasSubstr("expected min_echoes in [0, 255] (0: off), got 256"));
  EXPECT_EQ(with([](auto&) {}), "no error");

  LogOddsGrid g(5, 5, 1.0, Vec<2>::Zero());
  EXPECT_THAT(mapping_error(
                  [&] { g.integrate(Pose(std::nan(""), 0, 0), LaserMount{}, one_beam(0.0, 1.0)); }),
              HasSubstr("LogOddsGrid::integrate: expected a finite pose, got (nan, 0, 0)"));
  EXPECT_THAT(mapping_error([&] {
                g.integrate(Pose(0, 0, 0), LaserMount{0, INFINITY, 0}, one_beam(0.0, 1.0));
              }),
              HasSubstr("expected a finite laser mount, got (0, inf, 0)"));
  EXPECT_THAT(
      mapping_error([&] { g.integrate(Pose(0, 0, 0), LaserMount{}, one_beam(0.0, std::nan(""))); }),
      HasSubstr("LogOddsGrid::integrate: beam 0 has range nan"));
  EXPECT_THAT(mapping_error([] { LogOddsGrid(0, 5, 1.0, Vec<2>::Zero()); }),
              HasSubstr("expected a positive width and height, got 0 x 5"));

  const std::vector<Pose> poses = {Pose(0, 0, 0), Pose(1, 0, 0)};
  std::vector<LaserScan> scans = {one_beam(0.0, 1.0), one_beam(0.0, 2.0)};
  const LaserMount mount;
  const GridMappingOptions opt;
  EXPECT_THAT(mapping_error([&] { build_map(std::span(poses).first(1), scans, mount, opt); }),
              HasSubstr("expected one robot pose per scan, got 1 poses and 2 scans"));
  EXPECT_THAT(mapping_error([&] { build_map({}, {}, mount, opt); }),
              HasSubstr("expected at least one scan, got none"));
  const std::vector<Pose> bad_poses = {Pose(0, 0, 0), Pose(1, INFINITY, 0)};
  EXPECT_THAT(mapping_error([&] { build_map(bad_poses, scans, mount, opt); }),
              HasSubstr("expected finite robot poses, got (1, inf, 0) at pose 1"));
  scans[1].range_min = 9.0;
  EXPECT_THAT(mapping_error([&] { build_map(poses, scans, mount, opt); }),
              HasSubstr("build_map: scan 1: expected 0 <= range_min < range_max"));
  // No return from a 1 km laser, both ways: 2 km x 2 m at 5 cm is 40 000 x 41 cells... and
  // with a second beam north, 40 000 x 40 000: beyond 2^26.
  LaserScan far = one_beam(0.0, INFINITY, 1000.0);
  far.angle_min = 0.0;
  far.angle_increment = kPi / 2;
  far.ranges = {INFINITY, INFINITY, INFINITY, INFINITY};
  const std::vector<Pose> one_pose = {Pose(0, 0, 0)};
  const std::vector<LaserScan> far_scans = {far};
  EXPECT_THAT(mapping_error([&] { build_map(one_pose, far_scans, mount, opt); }),
              HasSubstr("build_map: expected a map of at most 67108864 cells, got 40041 x 40041 "
                        "cells of 0.05 m: x spans -1000 .. 1000 m and y spans -1000 .. 1000 m"));
  GridMappingOptions shorter = opt;
  shorter.max_range = 30.0;  // the way out the message suggests
  EXPECT_EQ(build_map(one_pose, far_scans, mount, shorter).width(), 1241);
}

// Scans in a square room with walls on the lines x = +-L and y = +-L, by exact geometry.
constexpr double kRoomHalf = 2.025;

double room_range(const Vec<2>& s, double a) {
  const double dx = std::cos(a), dy = std::sin(a);
  double r = std::numeric_limits<double>::infinity();
  if (dx != 0) r = std::min(r, ((dx > 0 ? kRoomHalf : -kRoomHalf) - s.x()) / dx);
  if (dy != 0) r = std::min(r, ((dy > 0 ? kRoomHalf : -kRoomHalf) - s.y()) / dy);
  return r;
}

TEST(GridMapping, SquareRoomFromKnownPosesHasItsWallsWhereTheyAre) {
  const LaserMount mount{0.1, 0.0, 0.0};
  const std::vector<Pose> poses = {Pose(0.0, 0.0, 0.0), Pose(0.35, -0.3, 1.0),
                                   Pose(-0.35, 0.35, 2.5), Pose(0.2, 0.35, -2.0)};
  std::vector<LaserScan> scans;
  for (const Pose& x : poses) {
    LaserScan s;
    s.angle_min = -kPi;
    s.angle_increment = 2 * kPi / 720;
    s.range_min = 0.05;
    s.range_max = 10.0;
    const Pose sensor = compose(x, Pose(mount.x, mount.y, mount.yaw));
    for (int i = 0; i < 720; ++i)
      s.ranges.push_back(room_range(sensor.head<2>(), sensor(2) + s.bearing(i)));
    scans.push_back(s);
  }
  GridMappingOptions opt;
  opt.margin = 0.5;
  const OccupancyGrid map = build_map(poses, scans, mount, opt);
  // The corner on a multiple of 5 cm below -2.025 - 0.5: -2.55; walls at cell centres.
  EXPECT_NEAR(map.origin().x(), -2.55, 1e-12);
  EXPECT_NEAR(map.origin().y(), -2.55, 1e-12);
  EXPECT_EQ(map.width(), 102);  // cells up to 2.525 m, at most 1 cell beyond the margin
  const double half_cell = 0.5 * map.resolution() + 1e-9;
  int wall_cells_checked = 0;
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix) {
      const Vec<2> c = map.cell_center(ix, iy);
      const double ax = std::abs(c.x()), ay = std::abs(c.y());
      const bool on_x_wall = std::abs(ax - kRoomHalf) < half_cell && ay < kRoomHalf + half_cell;
      const bool on_y_wall = std::abs(ay - kRoomHalf) < half_cell && ax < kRoomHalf + half_cell;
      const std::int8_t v = map.at(ix, iy);
      // Only wall cells hold beam end points, so only they can be occupied.
      if (!on_x_wall && !on_y_wall) {
        EXPECT_LT(v, OccupancyGrid::kOccupiedAt) << c.transpose();
      }
      // Inside, every cell is crossed by a beam of every pose (a cell 3.4 m away at most spans
      // at least 0.05 / 3.4 rad = 0.84 degree, more than the 0.5 degree beam spacing) and never
      // holds an end point: at least four misses, p <= 0.17.
      if (ax < kRoomHalf - half_cell && ay < kRoomHalf - half_cell) {
        EXPECT_TRUE(map.is_free(ix, iy)) << c.transpose() << " " << int(v);
      }
      // Outside the room no beam reaches.
      if (ax > kRoomHalf + half_cell || ay > kRoomHalf + half_cell) {
        EXPECT_EQ(v, OccupancyGrid::kUnknown) << c.transpose();
      }
      // The middle half of each wall faces every sensor (within 0.55 m of the centre) at 47
      // degrees or less, from 2.9 m at most: each of its cells spans at least 0.05 cos 47 / 2.9
      // rad = 0.67 degree, more than the beam spacing, so every pose hits it; a beam crosses a
      // wall cell without ending in it only in the last 2.5 cm before the wall line.
      if ((on_x_wall && ay < 1.0) || (on_y_wall && ax < 1.0)) {
        ++wall_cells_checked;
        EXPECT_TRUE(map.is_occupied(ix, iy)) << c.transpose() << " " << int(v);
      }
    }
  EXPECT_EQ(wall_cells_checked, 4 * 40);
}

}  // namespace
}  // namespace implicit::robot
