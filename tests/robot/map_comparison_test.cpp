// Scoring an estimated occupancy grid against a reference (spec §3.13.5): small grids whose
// counts are worked out by hand, a map against itself, a doubled wall, grids of other origins and
// resolutions, grids that share no known cell, and the options and inputs refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/map_comparison.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

// A grid drawn as a picture, top row (highest y) first: 'O' occupied (100), 'F' free (0), '.'
// unknown (-1).
OccupancyGrid picture(const std::vector<std::string>& rows, double resolution,
                      const Vec<2>& origin) {
  const int h = static_cast<int>(rows.size()), w = static_cast<int>(rows[0].size());
  OccupancyGrid g(w, h, resolution, origin);
  for (int iy = 0; iy < h; ++iy)
    for (int ix = 0; ix < w; ++ix) {
      const char c = rows[static_cast<std::size_t>(h - 1 - iy)][static_cast<std::size_t>(ix)];
      g.at(ix, iy) = c == 'O'   ? OccupancyGrid::kOccupied
                     : c == 'F' ? OccupancyGrid::kFree
                                : OccupancyGrid::kUnknown;
    }
  return g;
}

std::string comparison_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(MapComparison, HandWorkedGridsWithCellsAtTheThresholds) {
  // 1 m cells, same lattice. Reference and estimate (top row y = 2):
  //   OOOO    OOOF
  //   FFFF    FOF?     ? = 20: above kFreeAt, below kOccupiedAt: unknown
  //   FF..    ?FFO     ? = 64: unknown; (1, 0) = 19 (free, at kFreeAt); (3, 0) = 65 (occupied)
  const OccupancyGrid ref = picture({"OOOO", "FFFF", "FF.."}, 1.0, Vec<2>::Zero());
  OccupancyGrid est = picture({"OOOF", "FOF.", ".FFO"}, 1.0, Vec<2>::Zero());
  est.at(3, 1) = 20;
  est.at(0, 0) = 64;
  est.at(1, 0) = 19;
  est.at(3, 0) = 65;
  const MapComparison s = compare_maps(est, ref);
  EXPECT_EQ(s.tolerance_m, 1.0);  // one cell
  // Known in both: the top row (4), (0..2, 1) (3; (3, 1) is unknown in the estimate) and (1, 0)
  // ((0, 0) unknown in the estimate, (2..3, 0) in the reference): 8. Same class: (0..2, 2)
  // occupied, (0, 1), (2, 1) and (1, 0) free: 6 of 8.
  EXPECT_EQ(s.known_in_both, 8u);
  EXPECT_EQ(s.both_occupied, 3u);
  EXPECT_EQ(s.both_free, 3u);
  ASSERT_TRUE(s.agreement.has_value());
  EXPECT_DOUBLE_EQ(*s.agreement, 6.0 / 8.0);
  // Estimate occupied: (0..2, 2) on the reference's wall, (1, 1) one cell below it (matched
  // within 1 m), (3, 0) 2 m from the nearest, (3, 2): 4 of 5. Reference occupied: (0..2, 2)
  // coincide, (3, 2) has (2, 2) 1 m away: 4 of 4. F1 = 2 (0.8)(1) / 1.8 = 8/9.
  EXPECT_EQ(s.estimate_occupied, 5u);
  EXPECT_EQ(s.estimate_occupied_matched, 4u);
  EXPECT_EQ(s.reference_occupied, 4u);
  EXPECT_EQ(s.reference_occupied_matched, 4u);
  EXPECT_DOUBLE_EQ(s.occupied_precision.value(), 0.8);
  EXPECT_DOUBLE_EQ(s.occupied_recall.value(), 1.0);
  EXPECT_DOUBLE_EQ(s.occupied_f1.value(), 8.0 / 9.0);
  // Tolerance below one cell: only coinciding cells match, 3 of 5 and 3 of 4; F1 = 2 (0.6)(0.75)
  // / 1.35 = 2/3. The agreement does not depend on the tolerance.
  for (double t : {0.0, 0.99}) {
    const MapComparison z = compare_maps(est, ref, {.tolerance_m = t});
    EXPECT_EQ(z.tolerance_m, t);
    EXPECT_DOUBLE_EQ(*z.agreement, 0.75);
    EXPECT_EQ(z.estimate_occupied_matched, 3u) << t;
    EXPECT_EQ(z.reference_occupied_matched, 3u) << t;
    EXPECT_DOUBLE_EQ(z.occupied_f1.value(), 2.0 / 3.0) << t;
  }
  // (3, 0) is 2 m from (3, 2), its nearest reference wall cell: matched at 2 m, not at 1.99 m.
  EXPECT_EQ(compare_maps(est, ref, {.tolerance_m = 2.0}).estimate_occupied_matched, 5u);
  EXPECT_EQ(compare_maps(est, ref, {.tolerance_m = 1.99}).estimate_occupied_matched, 4u);
}

TEST(MapComparison, AMapAgainstItselfAgreesEverywhere) {
  const OccupancyGrid m =
      picture({"..OOOO..", ".OFFFFO.", ".OFFFFO.", ".OOOOOO."}, 0.05, Vec<2>(-3.7, 12.35));
  const MapComparison s = compare_maps(m, m);
  // Known: 4 + 6 + 6 + 6 = 22 cells, 14 occupied and 8 free.
  EXPECT_EQ(s.known_in_both, 22u);
  EXPECT_EQ(s.both_occupied, 14u);
  EXPECT_EQ(s.both_free, 8u);
  EXPECT_EQ(s.agreement, 1.0);
  EXPECT_EQ(s.estimate_occupied, 14u);
  EXPECT_EQ(s.reference_occupied, 14u);
  EXPECT_EQ(s.occupied_precision, 1.0);
  EXPECT_EQ(s.occupied_recall, 1.0);
  EXPECT_EQ(s.occupied_f1, 1.0);
}

// A 10 m x 6 m room in 0.5 m cells: free below a wall along row 8 (y in [1, 1.5)) over x cells
// 2..17, free beside the wall at x cells 0, 1, 18, 19, unknown behind it (rows 9..11).
OccupancyGrid room() {
  OccupancyGrid g(20, 12, 0.5, Vec<2>(-5.0, -3.0), OccupancyGrid::kFree);
  for (int ix = 2; ix <= 17; ++ix) g.at(ix, 8) = OccupancyGrid::kOccupied;
  for (int iy = 9; iy < 12; ++iy)
    for (int ix = 0; ix < 20; ++ix) g.at(ix, iy) = OccupancyGrid::kUnknown;
  return g;
}

TEST(MapComparison, AWallDoubledOneMetreAwayHalvesPrecisionAndKeepsRecall) {
  const OccupancyGrid ref = room();
  // In front of the wall: its copy 1 m (2 rows) lower, in the reference's free space. The 16
  // copied cells are 1 m from the wall, beyond the 0.5 m tolerance: precision 16/32, recall
  // 16/16, F1 = 2 (1/2) / (3/2) = 2/3. Known in both: rows 0..8, 180 cells, of which the 16
  // copied ones disagree (occupied against free).
  OccupancyGrid front = ref;
  for (int ix = 2; ix <= 17; ++ix) front.at(ix, 6) = OccupancyGrid::kOccupied;
  const MapComparison f = compare_maps(front, ref);
  EXPECT_EQ(f.estimate_occupied, 32u);
  EXPECT_EQ(f.estimate_occupied_matched, 16u);
  EXPECT_DOUBLE_EQ(f.occupied_precision.value(), 0.5);
  EXPECT_DOUBLE_EQ(f.occupied_recall.value(), 1.0);
  EXPECT_DOUBLE_EQ(f.occupied_f1.value(), 2.0 / 3.0);
  EXPECT_EQ(f.known_in_both, 180u);
  EXPECT_DOUBLE_EQ(f.agreement.value(), 164.0 / 180.0);
  // Behind the wall, where the reference saw nothing: the agreement cannot see the copy (1, as
  // against itself), precision still drops to 1/2.
  OccupancyGrid behind = ref;
  for (int ix = 2; ix <= 17; ++ix) behind.at(ix, 10) = OccupancyGrid::kOccupied;
  const MapComparison b = compare_maps(behind, ref);
  EXPECT_EQ(b.known_in_both, 180u);
  EXPECT_EQ(b.agreement, 1.0);
  EXPECT_DOUBLE_EQ(b.occupied_precision.value(), 0.5);
  EXPECT_DOUBLE_EQ(b.occupied_recall.value(), 1.0);
  // A tolerance of 1 m forgives the copy (exactly 1 m away).
  EXPECT_EQ(compare_maps(behind, ref, {.tolerance_m = 1.0}).occupied_precision, 1.0);
}

// `coarse` resampled to cells of half the size (each cell becomes 2 x 2), with a band of `pad`
// unknown fine cells around it: the same map, at another origin, extent and resolution.
OccupancyGrid refined(const OccupancyGrid& coarse, int pad) {
  const double r = coarse.resolution() / 2;
  OccupancyGrid g(2 * coarse.width() + 2 * pad, 2 * coarse.height() + 2 * pad, r,
                  coarse.origin() - Vec<2>(pad * r, pad * r));
  for (int iy = 0; iy < 2 * coarse.height(); ++iy)
    for (int ix = 0; ix < 2 * coarse.width(); ++ix)
      g.at(ix + pad, iy + pad) = coarse.at(ix / 2, iy / 2);
  return g;
}

TEST(MapComparison, OtherOriginsExtentsAndResolutionsAreComparedInTheWorld) {
  const OccupancyGrid coarse = room();            // 0.5 m: 16 occupied, 180 known cells
  const OccupancyGrid fine = refined(coarse, 3);  // 0.25 m, origin 0.75 m lower and further left
  // The fine estimate against the coarse reference: each coarse centre is a corner of four fine
  // cells of its own coarse cell, so the look-up finds the same class: agreement 1 over the 180
  // known coarse cells. The 64 fine occupied centres lie 0.25/sqrt(2) = 0.177 m from their
  // coarse cell's centre: all match within the default 0.5 m (the coarser cell).
  const MapComparison a = compare_maps(fine, coarse);
  EXPECT_EQ(a.tolerance_m, 0.5);
  EXPECT_EQ(a.known_in_both, 180u);
  EXPECT_EQ(a.agreement, 1.0);
  EXPECT_EQ(a.estimate_occupied, 64u);
  EXPECT_EQ(a.reference_occupied, 16u);
  EXPECT_EQ(a.occupied_precision, 1.0);
  EXPECT_EQ(a.occupied_recall, 1.0);
  // Within 0.18 m still all (0.1768 < 0.18); within 0.17 m none: P = R = 0, F1 = 0 by convention.
  EXPECT_EQ(compare_maps(fine, coarse, {.tolerance_m = 0.18}).occupied_f1, 1.0);
  const MapComparison none = compare_maps(fine, coarse, {.tolerance_m = 0.17});
  EXPECT_EQ(none.estimate_occupied_matched, 0u);
  EXPECT_EQ(none.reference_occupied_matched, 0u);
  EXPECT_EQ(none.occupied_precision, 0.0);
  EXPECT_EQ(none.occupied_recall, 0.0);
  EXPECT_EQ(none.occupied_f1, 0.0);
  // The other way round: every fine known cell's centre lies inside its coarse cell: 4 x 180.
  const MapComparison b = compare_maps(coarse, fine);
  EXPECT_EQ(b.known_in_both, 720u);
  EXPECT_EQ(b.agreement, 1.0);
  EXPECT_EQ(b.occupied_f1, 1.0);
}

TEST(MapComparison, AWallOneCellOffMatchesAtExactlyOneCell) {
  // 5 cm cells at an origin no multiple of them: the estimate is the reference moved one cell
  // (0.05 m) in x, so each occupied centre is 0.05 m, up to rounding, from its counterpart: the
  // wall is column 1 of the reference and column 2 of the reference's lattice in the estimate.
  const OccupancyGrid ref = picture({"FOFF", "FOFF", "FOFF"}, 0.05, Vec<2>(-3.7, 12.35));
  const OccupancyGrid est = picture({"FOFF", "FOFF", "FOFF"}, 0.05, Vec<2>(-3.65, 12.35));
  const MapComparison s = compare_maps(est, ref);
  EXPECT_EQ(s.occupied_precision, 1.0);
  EXPECT_EQ(s.occupied_recall, 1.0);
  // Of the 3 x 3 reference cells the estimate covers (x cells 1..3), world columns: reference
  // x = 1 (O) against estimate column 0 (F), x = 2 (F) against 1 (O), x = 3 (F) against 2 (F):
  // 3 of 9 agree. Reference column 0 lies outside the estimate.
  EXPECT_EQ(s.known_in_both, 9u);
  EXPECT_DOUBLE_EQ(s.agreement.value(), 3.0 / 9.0);
  const MapComparison strict = compare_maps(est, ref, {.tolerance_m = 0.049});
  EXPECT_EQ(strict.occupied_precision, 0.0);
  EXPECT_EQ(strict.occupied_recall, 0.0);
}

TEST(MapComparison, NoCellKnownInBothIsReportedWithoutDividingByZero) {
  const OccupancyGrid ref = room();
  // The same room 100 m away: nothing overlaps; the fractions with something to count are 0.
  OccupancyGrid far(20, 12, 0.5, Vec<2>(95.0, 97.0), OccupancyGrid::kFree);
  for (int ix = 2; ix <= 17; ++ix) far.at(ix, 8) = OccupancyGrid::kOccupied;
  const MapComparison s = compare_maps(far, ref);
  EXPECT_EQ(s.known_in_both, 0u);
  EXPECT_EQ(s.both_occupied + s.both_free, 0u);
  EXPECT_FALSE(s.agreement.has_value());
  EXPECT_EQ(s.estimate_occupied, 16u);
  EXPECT_EQ(s.occupied_precision, 0.0);
  EXPECT_EQ(s.occupied_recall, 0.0);
  EXPECT_EQ(s.occupied_f1, 0.0);
  // An estimate all unknown: no agreement, no precision and so no F1; recall 0 of 16.
  const OccupancyGrid blank(20, 12, 0.5, Vec<2>(-5.0, -3.0));
  const MapComparison u = compare_maps(blank, ref);
  EXPECT_EQ(u.known_in_both, 0u);
  EXPECT_FALSE(u.agreement.has_value());
  EXPECT_EQ(u.estimate_occupied, 0u);
  EXPECT_FALSE(u.occupied_precision.has_value());
  EXPECT_EQ(u.occupied_recall, 0.0);
  EXPECT_FALSE(u.occupied_f1.has_value());
  // And a reference without occupied cells: no recall.
  const OccupancyGrid empty_room(20, 12, 0.5, Vec<2>(-5.0, -3.0), OccupancyGrid::kFree);
  const MapComparison e = compare_maps(ref, empty_room);
  EXPECT_FALSE(e.occupied_recall.has_value());
  EXPECT_EQ(e.occupied_precision, 0.0);
  EXPECT_FALSE(e.occupied_f1.has_value());
  EXPECT_DOUBLE_EQ(e.agreement.value(), 164.0 / 180.0);  // the 16 wall cells disagree
}

TEST(MapComparison, RefusesBadTolerancesAndEmptyGrids) {
  const OccupancyGrid g = room();
  const auto with = [&](double t) {
    return comparison_error([&] { compare_maps(g, g, {.tolerance_m = t}); });
  };
  EXPECT_THAT(with(-0.1), HasSubstr("expected a finite tolerance_m >= 0 [m], got -0.1"));
  EXPECT_THAT(with(std::nan("")), HasSubstr("tolerance_m >= 0 [m], got nan"));
  EXPECT_THAT(with(std::numeric_limits<double>::infinity()),
              HasSubstr("tolerance_m >= 0 [m], got inf"));
  EXPECT_EQ(with(0.0), "no error");
  EXPECT_THAT(comparison_error([&] { compare_maps(OccupancyGrid(), g); }),
              HasSubstr("expected an estimate with cells, got an empty grid"));
  EXPECT_THAT(comparison_error([&] { compare_maps(g, OccupancyGrid()); }),
              HasSubstr("expected a reference with cells, got an empty grid"));
}

}  // namespace
}  // namespace implicit::robot
