// The distance transform against brute force, and the distance field's three interpolations
// against independent kernel sums, finite differences and continuity across cell patches.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/distance_field.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

// Squared distance, in cells, from every cell to the nearest occupied one: all pairs.
std::vector<double> brute_squared_distances(const std::vector<std::uint8_t>& occ, int w, int h) {
  std::vector<double> out(occ.size(), std::numeric_limits<double>::infinity());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int oy = 0; oy < h; ++oy)
        for (int ox = 0; ox < w; ++ox)
          if (occ[static_cast<std::size_t>(oy * w + ox)] != 0) {
            const double d = double(x - ox) * (x - ox) + double(y - oy) * (y - oy);
            double& best = out[static_cast<std::size_t>(y * w + x)];
            best = std::min(best, d);
          }
  return out;
}

std::vector<std::uint8_t> random_occupancy(Rng& rng, int w, int h, double density) {
  std::vector<std::uint8_t> occ(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (auto& o : occ) o = rng.uniform() < density ? 1 : 0;
  return occ;
}

TEST(DistanceTransform, EqualsBruteForceExactly) {
  Rng rng({41, 0, 0, purpose::kUser});
  const int sizes[][2] = {{1, 1}, {1, 9}, {9, 1}, {2, 2}, {5, 8}, {17, 13}, {40, 31}};
  for (const auto& s : sizes)
    for (const double density : {0.0, 0.005, 0.05, 0.3, 0.8, 1.0}) {
      const auto occ = random_occupancy(rng, s[0], s[1], density);
      const auto fast = squared_distance_transform(occ, s[0], s[1]);
      const auto slow = brute_squared_distances(occ, s[0], s[1]);
      ASSERT_EQ(fast.size(), slow.size());
      for (std::size_t k = 0; k < fast.size(); ++k)
        ASSERT_EQ(fast[k], slow[k])
            << s[0] << " x " << s[1] << " density " << density << " cell " << k;
    }
}

TEST(DistanceTransform, NoOccupiedCellGivesInfinityAndOneCellGivesTheSquaredOffsets) {
  const std::vector<std::uint8_t> none(12, 0);
  for (const double d : squared_distance_transform(none, 4, 3))
    EXPECT_EQ(d, std::numeric_limits<double>::infinity());
  std::vector<std::uint8_t> one(12, 0);
  one[1 * 4 + 2] = 1;  // (x, y) = (2, 1)
  const auto d = squared_distance_transform(one, 4, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(d[y * 4 + x], (x - 2) * (x - 2) + (y - 1) * (y - 1));
}

TEST(DistanceTransform, RefusesSizesThatDisagree) {
  const std::vector<std::uint8_t> cells(6, 0);
  try {
    squared_distance_transform(cells, 4, 2);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("expected 4 x 2 = 8 cells, got 6"));
  }
  EXPECT_THROW(squared_distance_transform(cells, 0, 6), InvalidArgument);
}

OccupancyGrid random_grid(Rng& rng, int w, int h, double res, const Vec<2>& origin,
                          double density) {
  OccupancyGrid g(w, h, res, origin, OccupancyGrid::kFree);
  for (int iy = 0; iy < h; ++iy)
    for (int ix = 0; ix < w; ++ix)
      if (rng.uniform() < density) g.at(ix, iy) = OccupancyGrid::kOccupied;
  return g;
}

TEST(DistanceField, CellDistancesEqualBruteForceAndEveryModeReproducesThem) {
  Rng rng({42, 0, 0, purpose::kUser});
  const double max_d = 0.9;
  const OccupancyGrid g = random_grid(rng, 23, 19, 0.1, Vec<2>(-1.3, 0.7), 0.03);
  const DistanceField f(g, max_d);
  std::vector<std::uint8_t> occ(g.data().size());
  for (std::size_t k = 0; k < occ.size(); ++k) occ[k] = g.data()[k] >= OccupancyGrid::kOccupiedAt;
  const auto sq = brute_squared_distances(occ, 23, 19);
  for (int iy = 0; iy < 19; ++iy)
    for (int ix = 0; ix < 23; ++ix) {
      // Stored as float: exactly the float nearest the capped brute-force distance.
      const double expected =
          static_cast<float>(std::min(std::sqrt(sq[iy * 23 + ix]) * 0.1, f.max_distance()));
      ASSERT_EQ(f.cell_distance(ix, iy), expected) << ix << ", " << iy;
      const Vec<2> c = g.cell_center(ix, iy);
      for (const auto mode :
           {Interpolation::kNearest, Interpolation::kBilinear, Interpolation::kBicubic})
        EXPECT_NEAR(f.distance(c, mode), expected, 1e-12) << ix << ", " << iy;
    }
  EXPECT_EQ(f.max_distance(), static_cast<float>(max_d));
  EXPECT_EQ(f.cell_distance(-1, 0), f.max_distance());
  EXPECT_EQ(f.cell_distance(0, 19), f.max_distance());
}

TEST(DistanceField, OneObstacleGivesTheClosedForm) {
  OccupancyGrid g(30, 20, 0.25, Vec<2>(5.0, -5.0), OccupancyGrid::kFree);
  g.at(7, 12) = 65;  // occupied from kOccupiedAt on
  g.at(20, 3) = 64;  // not occupied
  const DistanceField f(g, 3.0);
  for (int iy = 0; iy < 20; ++iy)
    for (int ix = 0; ix < 30; ++ix)
      EXPECT_NEAR(f.cell_distance(ix, iy), std::min(0.25 * std::hypot(ix - 7, iy - 12), 3.0),
                  3.0 * 1e-7);  // float storage: relative rounding 2^-24
  const OccupancyGrid empty(6, 5, 0.5, Vec<2>::Zero(), OccupancyGrid::kFree);
  const DistanceField none(empty, 1.5);
  EXPECT_EQ(none.cell_distance(3, 3), 1.5);
  EXPECT_EQ(none.distance(Vec<2>(1.3, 1.1), Interpolation::kBicubic), 1.5);
}

// The interpolation written as a sum over cells of a kernel of the distance to each centre:
// Keys' cubic (a = -1/2) or the tent. Independent of the implementation's 4 x 4 patches, its
// padding and its weights per offset.
double keys_kernel(double x) {
  x = std::abs(x);
  if (x < 1) return 1.5 * x * x * x - 2.5 * x * x + 1;
  if (x < 2) return -0.5 * x * x * x + 2.5 * x * x - 4 * x + 2;
  return 0.0;
}
double tent_kernel(double x) { return std::max(0.0, 1 - std::abs(x)); }

double kernel_sum(const DistanceField& f, const Vec<2>& p, double (*kernel)(double)) {
  const double u = (p.x() - f.origin().x()) / f.resolution() - 0.5;
  const double v = (p.y() - f.origin().y()) / f.resolution() - 0.5;
  double s = 0.0;
  const int i0 = static_cast<int>(std::floor(u)), j0 = static_cast<int>(std::floor(v));
  for (int j = j0 - 3; j <= j0 + 3; ++j)
    for (int i = i0 - 3; i <= i0 + 3; ++i)
      s += kernel(u - i) * kernel(v - j) * f.cell_distance(i, j);
  return s;
}

TEST(DistanceField, InterpolationEqualsTheKernelSumInsideAndAroundTheGrid) {
  Rng rng({43, 0, 0, purpose::kUser});
  const OccupancyGrid g = random_grid(rng, 12, 9, 0.2, Vec<2>(1.0, -2.0), 0.08);
  const DistanceField f(g, 0.7);
  for (int k = 0; k < 4000; ++k) {
    // Up to 6 cells outside the grid on every side, the band where padding runs out included.
    const double ux = rng.uniform(), uy = rng.uniform();  // in this order
    const Vec<2> p(1.0 - 1.2 + 3.6 * ux, -2.0 - 1.2 + 4.2 * uy);
    const Vec<2> bad = Vec<2>::Constant(std::nan(""));
    Vec<2> grad = bad;
    EXPECT_NEAR(f.distance(p, Interpolation::kBicubic, &grad), kernel_sum(f, p, keys_kernel), 1e-12)
        << p.transpose();
    EXPECT_TRUE(grad.allFinite());
    EXPECT_NEAR(f.distance(p, Interpolation::kBilinear), kernel_sum(f, p, tent_kernel), 1e-12)
        << p.transpose();
    const Eigen::Vector2i c = g.cell_of(p);
    grad = bad;
    EXPECT_EQ(f.distance(p, Interpolation::kNearest, &grad), f.cell_distance(c.x(), c.y()));
    EXPECT_EQ(grad, Vec<2>::Zero());
  }
}

TEST(DistanceField, FarOutsideIsMaxDistanceAndNanIsNan) {
  const OccupancyGrid g(4, 4, 1.0, Vec<2>::Zero(), OccupancyGrid::kOccupied);
  const DistanceField f(g, 2.5);
  for (const auto mode :
       {Interpolation::kNearest, Interpolation::kBilinear, Interpolation::kBicubic}) {
    Vec<2> grad(1.0, 1.0);
    EXPECT_EQ(f.distance(Vec<2>(-30.0, 2.0), mode, &grad), 2.5);
    EXPECT_EQ(grad, Vec<2>::Zero());
    EXPECT_EQ(f.distance(Vec<2>(2.0, 1e300), mode), 2.5);
    EXPECT_EQ(f.distance(Vec<2>(-INFINITY, 2.0), mode), 2.5);
    EXPECT_TRUE(std::isnan(f.distance(Vec<2>(std::nan(""), 2.0), mode, &grad)));
    EXPECT_TRUE(grad.array().isNaN().all());
  }
  EXPECT_EQ(f.distance(Vec<2>(2.0, 2.0), Interpolation::kBicubic), 0.0);
  const DistanceField empty;
  EXPECT_EQ(empty.distance(Vec<2>(0.0, 0.0), Interpolation::kBicubic), 0.0);
}

// Central differences of the field at p with step h [m].
Vec<2> central_difference(const DistanceField& f, const Vec<2>& p, Interpolation mode, double h) {
  Vec<2> g;
  for (int k = 0; k < 2; ++k) {
    Vec<2> a = p, b = p;
    a(k) += h;
    b(k) -= h;
    g(k) = (f.distance(a, mode) - f.distance(b, mode)) / (2 * h);
  }
  return g;
}

// A random point whose offsets from the cell centres, in cells, lie in [margin, 1 - margin]:
// away from the seams between interpolation patches.
Vec<2> point_between_seams(Rng& rng, const DistanceField& f, double margin) {
  const double res = f.resolution();
  auto coordinate = [&](double origin, int cells) {
    const int i = static_cast<int>(rng.uniform() * (cells + 6)) - 3;
    return origin + (i + 0.5 + margin + (1 - 2 * margin) * rng.uniform()) * res;
  };
  return Vec<2>(coordinate(f.origin().x(), f.width()), coordinate(f.origin().y(), f.height()));
}

TEST(DistanceField, GradientsMatchFiniteDifferences) {
  Rng rng({44, 0, 0, purpose::kUser});
  const double res = 0.1, max_d = 1.0;
  const OccupancyGrid g = random_grid(rng, 15, 11, res, Vec<2>(-0.4, 0.3), 0.06);
  const DistanceField f(g, max_d);
  // Bilinear: linear along each axis inside a patch, so the central difference is exact up to
  // rounding, about eps * max_d / h = 2e-11 with h = 1e-5 m.
  // Bicubic: the central difference errs by at most h^2 / 6 |f'''|; along x, |f'''| <= (sum of
  // |w'''| = 24) * (max sum of |w_y| = 1.25) * max_d / res^3 = 3e4 per m^3: 5e-7 with h = 1e-5.
  const double h = 1e-5;
  for (int k = 0; k < 2000; ++k) {
    const Vec<2> p = point_between_seams(rng, f, 0.01);
    Vec<2> grad;
    f.distance(p, Interpolation::kBilinear, &grad);
    EXPECT_LT(
        (grad - central_difference(f, p, Interpolation::kBilinear, h)).lpNorm<Eigen::Infinity>(),
        1e-9)
        << p.transpose();
    f.distance(p, Interpolation::kBicubic, &grad);
    EXPECT_LT(
        (grad - central_difference(f, p, Interpolation::kBicubic, h)).lpNorm<Eigen::Infinity>(),
        5e-7)
        << p.transpose();
  }
}

TEST(DistanceField, BicubicValueAndGradientAreContinuousAcrossSeams) {
  Rng rng({45, 0, 0, purpose::kUser});
  const double res = 0.1;
  const OccupancyGrid g = random_grid(rng, 15, 11, res, Vec<2>(-0.4, 0.3), 0.06);
  const DistanceField f(g, 1.0);
  // The seams are the lines through cell centres. delta = 1e-9 m either side: a C1 field
  // changes there by at most |f'| 2 delta (value) and |f''| 2 delta (gradient). Over t in [0, 1]
  // the four weights have sum |w| <= 1.25, sum |w'| <= 3 and sum |w''| <= 12, so with values in
  // [0, max_d]: |f'| <= 3 * 1.25 * max_d / res < 50 per m, and |f_xx| <= 12 * 1.25 * max_d /
  // res^2, |f_xy| <= 3 * 3 * max_d / res^2, both < 1750 per m^2. Were it not C1, the gradient
  // would jump by O(max_d / res) = O(10).
  const double delta = 1e-9;
  for (int k = 0; k < 2000; ++k) {
    Vec<2> p = point_between_seams(rng, f, 0.0);
    const int axis = k % 2;
    const double seam_cells = std::round((p(axis) - f.origin()(axis)) / res - 0.5) + 0.5;
    p(axis) = f.origin()(axis) + seam_cells * res;
    Vec<2> a = p, b = p, ga, gb, gb_linear, ga_linear;
    a(axis) -= delta;
    b(axis) += delta;
    const double va = f.distance(a, Interpolation::kBicubic, &ga);
    const double vb = f.distance(b, Interpolation::kBicubic, &gb);
    EXPECT_NEAR(va, vb, 2 * delta * 50 + 1e-12) << p.transpose();
    EXPECT_LT((ga - gb).lpNorm<Eigen::Infinity>(), 2 * delta * 1750 + 1e-9) << p.transpose();
    // Bilinear is continuous too (its gradient is not).
    EXPECT_NEAR(f.distance(a, Interpolation::kBilinear), f.distance(b, Interpolation::kBilinear),
                2 * delta * 2 * 1.0 / res + 1e-12);
  }
}

TEST(DistanceField, RefusesEmptyGridsAndBadMaxDistance) {
  const OccupancyGrid g(3, 3, 0.1, Vec<2>::Zero(), 0);
  auto message = [](const std::function<void()>& fn) -> std::string {
    try {
      fn();
    } catch (const InvalidArgument& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(message([&] { DistanceField(OccupancyGrid(), 1.0); }),
              HasSubstr("expected a grid with cells, got an empty one"));
  for (const double bad : {0.0, -1.0, std::nan(""), double(INFINITY)})
    EXPECT_THAT(message([&] { DistanceField(g, bad); }),
                HasSubstr("expected a positive, finite max_distance [m], got"));
  EXPECT_THAT(message([&] { DistanceField(g, 1e300); }),
              HasSubstr("expected a max_distance [m] within the range of float"));
}

}  // namespace
}  // namespace implicit::robot
