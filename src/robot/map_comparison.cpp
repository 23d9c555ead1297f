#include "implicit/robot/map_comparison.hpp"

#include <algorithm>
#include <cmath>

#include "implicit/core/error.hpp"

namespace implicit::robot {

void MapComparisonOptions::validate() const {
  if (!tolerance_m) return;
  require(std::isfinite(*tolerance_m) && *tolerance_m >= 0,
          "MapComparisonOptions: expected a finite tolerance_m >= 0 [m], got {}", *tolerance_m);
}

namespace {

enum class CellClass { kUnknown, kFree, kOccupied };

CellClass class_of(const OccupancyGrid& g, int ix, int iy) {
  if (g.is_occupied(ix, iy)) return CellClass::kOccupied;
  if (g.is_free(ix, iy)) return CellClass::kFree;
  return CellClass::kUnknown;
}

// The estimate's class at world point p: unknown outside its extent.
CellClass class_at(const OccupancyGrid& g, const Vec<2>& p) {
  const Eigen::Vector2i c = g.cell_of(p);
  return g.contains(c.x(), c.y()) ? class_of(g, c.x(), c.y()) : CellClass::kUnknown;
}

// The index range [lo, hi] of g's cells along one axis whose centres may lie within t of q
// (coordinate q, origin o, resolution r), clamped to [0, n - 1]: the bounds are rounded outward
// and the distance test decides, so that rounding cannot drop a cell at the tolerance.
void window(double q, double t, double o, double r, int n, int* lo, int* hi) {
  const double a = std::floor((q - t - o) / r - 0.5), b = std::ceil((q + t - o) / r - 0.5);
  *lo = static_cast<int>(std::clamp(a, 0.0, static_cast<double>(n)));
  *hi = static_cast<int>(std::clamp(b, -1.0, static_cast<double>(n - 1)));
}

// Whether an occupied cell of `other` has its centre within t of p (squared distance compared
// with t^2 plus the slack).
bool occupied_within(const OccupancyGrid& other, const Vec<2>& p, double t, double t2) {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  window(p.x(), t, other.origin().x(), other.resolution(), other.width(), &x0, &x1);
  window(p.y(), t, other.origin().y(), other.resolution(), other.height(), &y0, &y1);
  for (int iy = y0; iy <= y1; ++iy)
    for (int ix = x0; ix <= x1; ++ix)
      if (other.is_occupied(ix, iy) && (other.cell_center(ix, iy) - p).squaredNorm() <= t2)
        return true;
  return false;
}

// Counts g's occupied cells and those with an occupied cell of `other` within t.
void match_occupied(const OccupancyGrid& g, const OccupancyGrid& other, double t,
                    std::size_t* occupied, std::size_t* matched) {
  // Cells exactly t apart (neighbours at t = one cell) differ from t by rounding either way.
  const double t2 = t * t + 1e-9 * std::max(t * t, other.resolution() * other.resolution());
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      if (!g.is_occupied(ix, iy)) continue;
      ++*occupied;
      if (occupied_within(other, g.cell_center(ix, iy), t, t2)) ++*matched;
    }
}

std::optional<double> fraction(std::size_t part, std::size_t whole) {
  if (whole == 0) return std::nullopt;
  return static_cast<double>(part) / static_cast<double>(whole);
}

}  // namespace

MapComparison compare_maps(const OccupancyGrid& estimate, const OccupancyGrid& reference,
                           const MapComparisonOptions& options) {
  options.validate();
  require(!estimate.empty(), "compare_maps: expected an estimate with cells, got an empty grid");
  require(!reference.empty(), "compare_maps: expected a reference with cells, got an empty grid");
  MapComparison s;
  s.tolerance_m =
      options.tolerance_m.value_or(std::max(estimate.resolution(), reference.resolution()));
  for (int iy = 0; iy < reference.height(); ++iy)
    for (int ix = 0; ix < reference.width(); ++ix) {
      const CellClass r = class_of(reference, ix, iy);
      if (r == CellClass::kUnknown) continue;
      const CellClass e = class_at(estimate, reference.cell_center(ix, iy));
      if (e == CellClass::kUnknown) continue;
      ++s.known_in_both;
      if (e == r) ++(r == CellClass::kOccupied ? s.both_occupied : s.both_free);
    }
  s.agreement = fraction(s.both_occupied + s.both_free, s.known_in_both);
  match_occupied(estimate, reference, s.tolerance_m, &s.estimate_occupied,
                 &s.estimate_occupied_matched);
  match_occupied(reference, estimate, s.tolerance_m, &s.reference_occupied,
                 &s.reference_occupied_matched);
  s.occupied_precision = fraction(s.estimate_occupied_matched, s.estimate_occupied);
  s.occupied_recall = fraction(s.reference_occupied_matched, s.reference_occupied);
  if (s.occupied_precision && s.occupied_recall) {
    const double p = *s.occupied_precision, r = *s.occupied_recall;
    s.occupied_f1 = p + r > 0 ? 2 * p * r / (p + r) : 0.0;
  }
  return s;
}

}  // namespace implicit::robot
