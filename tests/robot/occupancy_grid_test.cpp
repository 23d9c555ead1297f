// Occupancy grids and ray casting: cell arithmetic, hand-computed rays, and random rays against
// an independent computation (the entry of the ray into every occupied cell's box).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

std::string grid_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(OccupancyGrid, RefusesBadSizesResolutionOriginAndFill) {
  const Vec<2> o = Vec<2>::Zero();
  EXPECT_THAT(grid_error([&] { OccupancyGrid(0, 5, 0.1, o); }),
              HasSubstr("expected a positive width and height, got 0 x 5"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, -1, 0.1, o); }),
              HasSubstr("expected a positive width and height, got 5 x -1"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, 5, 0.0, o); }),
              HasSubstr("expected a positive, finite resolution [m], got 0"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, 5, std::nan(""), o); }),
              HasSubstr("finite resolution [m], got nan"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, 5, 0.1, Vec<2>(0.0, INFINITY)); }),
              HasSubstr("expected a finite origin, got (0, inf)"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, 5, 0.1, o, 101); }),
              HasSubstr("expected a fill value in -1..100, got 101"));
  EXPECT_THAT(grid_error([&] { OccupancyGrid(5, 5, 0.1, o, -2); }),
              HasSubstr("expected a fill value in -1..100, got -2"));
  // 65536 x 32769 is one row more than 2^31 cells: refused before anything is allocated.
  EXPECT_THAT(grid_error([&] { OccupancyGrid(65536, 32769, 0.1, o); }),
              HasSubstr("expected at most 2^31 cells, got 65536 x 32769 = 2147549184"));
}

TEST(OccupancyGrid, CellsAndCentres) {
  OccupancyGrid g(4, 3, 0.5, Vec<2>(-1.0, 2.0), OccupancyGrid::kFree);
  EXPECT_EQ(g.width(), 4);
  EXPECT_EQ(g.height(), 3);
  EXPECT_EQ(g.data().size(), 12u);
  EXPECT_TRUE(g.is_free(3, 2));
  g.at(3, 2) = OccupancyGrid::kOccupied;
  EXPECT_EQ(g.data()[2 * 4 + 3], OccupancyGrid::kOccupied);  // row-major, row 0 the lowest y
  EXPECT_TRUE(g.is_occupied(3, 2));
  g.at(0, 0) = 64;
  EXPECT_FALSE(g.is_occupied(0, 0));
  EXPECT_FALSE(g.is_free(0, 0));
  g.at(0, 0) = 65;
  EXPECT_TRUE(g.is_occupied(0, 0));
  g.at(0, 0) = 19;
  EXPECT_TRUE(g.is_free(0, 0));
  g.at(0, 0) = OccupancyGrid::kUnknown;
  EXPECT_FALSE(g.is_free(0, 0));

  EXPECT_EQ(g.cell_center(0, 0), Vec<2>(-0.75, 2.25));
  EXPECT_EQ(g.cell_center(3, 2), Vec<2>(0.75, 3.25));
  EXPECT_EQ(g.cell_of(Vec<2>(-0.75, 2.25)), Eigen::Vector2i(0, 0));
  EXPECT_EQ(g.cell_of(Vec<2>(-1.0, 2.0)), Eigen::Vector2i(0, 0));      // lower-left corner: inside
  EXPECT_EQ(g.cell_of(Vec<2>(1.0, 3.5)), Eigen::Vector2i(4, 3));       // upper-right: outside
  EXPECT_EQ(g.cell_of(Vec<2>(-1.01, 1.99)), Eigen::Vector2i(-1, -1));  // floor, not truncation
  EXPECT_EQ(g.cell_of(Vec<2>(1e300, -1e300)),
            Eigen::Vector2i(std::numeric_limits<int>::max(), std::numeric_limits<int>::min()));
  for (int iy = 0; iy < 3; ++iy)
    for (int ix = 0; ix < 4; ++ix)
      EXPECT_EQ(g.cell_of(g.cell_center(ix, iy)), Eigen::Vector2i(ix, iy));
  EXPECT_THAT(grid_error([&] { g.cell_of(Vec<2>(std::nan(""), 0.0)); }),
              HasSubstr("cell_of: expected a point, got (nan, 0)"));
}

// A 10 x 10 grid of 0.5 m cells, origin (-1, -2); rays from the centre of cell (1, 3), which is
// the world point (-0.25, -0.25).
OccupancyGrid ray_grid() { return OccupancyGrid(10, 10, 0.5, Vec<2>(-1.0, -2.0), 0); }

TEST(CastRay, AxisAlignedRaysStopAtTheNearSideOfTheFirstOccupiedCell) {
  OccupancyGrid g = ray_grid();
  g.at(6, 3) = OccupancyGrid::kOccupied;  // x in [2, 2.5)
  g.at(8, 3) = OccupancyGrid::kOccupied;  // behind it: never reached
  g.at(1, 8) = OccupancyGrid::kOccupied;  // y in [2, 2.5)
  g.at(1, 0) = OccupancyGrid::kOccupied;  // y in [-2, -1.5): its top side is at -1.5
  const Vec<2> from(-0.25, -0.25);
  EXPECT_NEAR(cast_ray(g, from, 0.0, 20.0), 2.25, 1e-12);
  EXPECT_NEAR(cast_ray(g, from, kPi / 2, 20.0), 2.25, 1e-12);
  EXPECT_NEAR(cast_ray(g, from, -kPi / 2, 20.0), 1.25, 1e-12);
  EXPECT_NEAR(cast_ray(g, from, 2 * kPi, 20.0), 2.25, 1e-12);  // angles need not be wrapped
  // Westwards nothing is occupied: the ray leaves the grid (at 0.75 m) and reports max_range.
  EXPECT_EQ(cast_ray(g, from, kPi, 20.0), 20.0);
  // A wall beyond max_range is not seen.
  EXPECT_EQ(cast_ray(g, from, 0.0, 2.0), 2.0);
  EXPECT_EQ(cast_ray(g, from, 0.0, 2.25), 2.25);
  EXPECT_EQ(cast_ray(g, from, 0.0, 0.0), 0.0);
}

TEST(CastRay, DiagonalRaysCrossTheCellsByHand) {
  // Cell units (resolution 1, origin 0), from (0.5, 0.5) along (2, 1)/sqrt(5): the ray is at
  // (0.5 + 2s, 0.5 + s) after sqrt(5) s, and crosses x = 1, y = 1, x = 2, x = 3, y = 2 at
  // s = 0.25, 0.5, 0.75, 1.25, 1.5: cells (0,0) (1,0) (1,1) (2,1) (3,1) (3,2) ...
  OccupancyGrid g(8, 8, 1.0, Vec<2>::Zero(), 0);
  g.at(2, 0) = OccupancyGrid::kOccupied;  // beside the path, not on it
  g.at(1, 2) = OccupancyGrid::kOccupied;  // likewise
  g.at(3, 2) = OccupancyGrid::kOccupied;  // entered at s = 1.5
  const double angle = std::atan2(1.0, 2.0);
  EXPECT_NEAR(cast_ray(g, Vec<2>(0.5, 0.5), angle, 100.0), 1.5 * std::sqrt(5.0), 1e-12);
  g.at(3, 1) = OccupancyGrid::kOccupied;  // now entered at s = 1.25
  EXPECT_NEAR(cast_ray(g, Vec<2>(0.5, 0.5), angle, 100.0), 1.25 * std::sqrt(5.0), 1e-12);

  // At 45 degrees from the centre of (1, 3) of the 0.5 m grid the ray runs through the corners
  // (2, 4), (3, 5), (4, 6) (in cells): cell (4, 6) is entered after 2.5 sqrt(2) cells.
  OccupancyGrid h = ray_grid();
  h.at(4, 6) = OccupancyGrid::kOccupied;
  EXPECT_NEAR(cast_ray(h, Vec<2>(-0.25, -0.25), kPi / 4, 20.0), 2.5 * std::sqrt(2.0) * 0.5, 1e-12);
  // A wall drawn as a staircase of cells that touch only at corners stops the ray too: it
  // reaches the first corner after sqrt(2) / 2 cells.
  OccupancyGrid s = ray_grid();
  s.at(2, 3) = OccupancyGrid::kOccupied;
  s.at(1, 4) = OccupancyGrid::kOccupied;
  EXPECT_NEAR(cast_ray(s, Vec<2>(-0.25, -0.25), kPi / 4, 20.0), std::sqrt(2.0) / 2 * 0.5, 1e-12);
}

TEST(CastRay, StartsInsideAnOccupiedCellOrOutsideTheGrid) {
  OccupancyGrid g = ray_grid();
  g.at(1, 3) = OccupancyGrid::kOccupied;
  EXPECT_EQ(cast_ray(g, Vec<2>(-0.25, -0.25), 1.0, 20.0), 0.0);
  EXPECT_EQ(cast_ray(g, Vec<2>(-0.5, -0.5), 1.0, 20.0), 0.0);  // its lower-left corner
  // From 3 m west of the grid, eastwards along y = -0.25: the grid starts at x = -1, and cell
  // (0, 3) is the first occupied one.
  g.at(0, 3) = OccupancyGrid::kOccupied;
  EXPECT_NEAR(cast_ray(g, Vec<2>(-4.0, -0.25), 0.0, 20.0), 3.0, 1e-12);
  EXPECT_EQ(cast_ray(g, Vec<2>(-4.0, -0.25), 0.0, 2.0), 2.0);    // stops short of the grid
  EXPECT_EQ(cast_ray(g, Vec<2>(-4.0, -0.25), kPi, 20.0), 20.0);  // away from it
  EXPECT_EQ(cast_ray(g, Vec<2>(-4.0, 10.0), 0.0, 20.0), 20.0);   // passes above it
  // From the east, the ray enters through the far side (x = 4) into the last column.
  g.at(9, 3) = OccupancyGrid::kOccupied;
  EXPECT_NEAR(cast_ray(g, Vec<2>(5.0, -0.25), kPi, 20.0), 1.0, 1e-12);
}

TEST(CastRay, RefusesNonFiniteInputAndEmptyGrids) {
  const OccupancyGrid g = ray_grid();
  const double nan = std::nan("");
  EXPECT_THAT(grid_error([&] { cast_ray(g, Vec<2>(nan, 0.0), 0.0, 1.0); }),
              HasSubstr("cast_ray: expected a finite start and angle, got (nan, 0) and 0"));
  EXPECT_THAT(grid_error([&] { cast_ray(g, Vec<2>(0.0, 0.0), INFINITY, 1.0); }),
              HasSubstr("got (0, 0) and inf"));
  EXPECT_THAT(grid_error([&] { cast_ray(g, Vec<2>(0.0, 0.0), 0.0, nan); }),
              HasSubstr("expected a finite max_range >= 0, got nan"));
  EXPECT_THAT(grid_error([&] { cast_ray(g, Vec<2>(0.0, 0.0), 0.0, INFINITY); }),
              HasSubstr("expected a finite max_range >= 0, got inf"));
  EXPECT_THAT(grid_error([&] { cast_ray(g, Vec<2>(0.0, 0.0), 0.0, -1.0); }),
              HasSubstr("expected a finite max_range >= 0, got -1"));
  EXPECT_THAT(grid_error([&] { cast_ray(OccupancyGrid(), Vec<2>(0.0, 0.0), 0.0, 1.0); }),
              HasSubstr("expected a grid with cells, got an empty one"));
}

// Where ray from + t (cos a, sin a) enters the box of cell (ix, iy), by the slab method; +inf
// if it misses it (or only touches it).
double enters_cell_at(const OccupancyGrid& g, const Vec<2>& from, double a, int ix, int iy) {
  const Vec<2> lo = g.origin() + g.resolution() * Vec<2>(ix, iy);
  const Vec<2> hi = lo + Vec<2>::Constant(g.resolution());
  const Vec<2> d(std::cos(a), std::sin(a));
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 2; ++k) {
    if (d(k) == 0) {
      if (from(k) < lo(k) || from(k) >= hi(k)) return t1;
      continue;
    }
    const double a0 = (lo(k) - from(k)) / d(k), a1 = (hi(k) - from(k)) / d(k);
    t0 = std::max(t0, std::min(a0, a1));
    t1 = std::min(t1, std::max(a0, a1));
  }
  return t0 < t1 ? t0 : std::numeric_limits<double>::infinity();
}

TEST(CastRay, RandomRaysMatchTheNearestCellBoxEntry) {
  Rng rng({31, 0, 0, purpose::kUser});
  for (int trial = 0; trial < 40; ++trial) {
    OccupancyGrid g(23, 17, 0.3, Vec<2>(-2.0, 1.0), 0);
    const double density = trial % 4 == 0 ? 0.02 : 0.15;
    for (int iy = 0; iy < g.height(); ++iy)
      for (int ix = 0; ix < g.width(); ++ix)
        if (rng.uniform() < density) g.at(ix, iy) = OccupancyGrid::kOccupied;
    for (int ray = 0; ray < 50; ++ray) {
      // Starts inside the grid and up to 2 m outside it.
      const double ux = rng.uniform(), uy = rng.uniform();  // in this order
      const Vec<2> from(-4.0 + 10.9 * ux, -1.0 + 9.1 * uy);
      const double a = 2 * kPi * rng.uniform() - kPi;
      const double max_range = 12.0 * rng.uniform();
      double expected = max_range;
      for (int iy = 0; iy < g.height(); ++iy)
        for (int ix = 0; ix < g.width(); ++ix)
          if (g.is_occupied(ix, iy))
            expected = std::min(expected, enters_cell_at(g, from, a, ix, iy));
      EXPECT_NEAR(cast_ray(g, from, a, max_range), expected, 1e-9)
          << "from (" << from.transpose() << ") at " << a << " up to " << max_range;
    }
  }
}

}  // namespace
}  // namespace implicit::robot
