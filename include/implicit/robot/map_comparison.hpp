#pragma once
// Scoring an estimated occupancy grid against a reference one in the same world frame: a SLAM
// map against the map built from the reference poses (spec §3.13.5).
//
//   OccupancyGrid truth = build_map(reference_poses, scans, mount, options);   // grid_mapping.hpp
//   MapComparison s = compare_maps(slam_map, truth);           // tolerance: one cell
//   if (s.agreement) ...                                       // nullopt: nothing known in both
//   s.occupied_precision; s.occupied_recall; s.occupied_f1;
//
// Each cell is occupied (value >= OccupancyGrid::kOccupiedAt), free (0 .. kFreeAt) or unknown
// (the rest, -1 included), the thresholds every OccupancyGrid uses. The grids may differ in
// origin, extent and resolution:
//   - agreement is taken at the reference's cell centres, the estimate's class being that of its
//     cell holding the centre (unknown outside the estimate): of the cells known in both, the
//     fraction whose class is the same;
//   - occupied precision is the fraction of the estimate's occupied cells (each grid's cells are
//     its own) whose centre lies within tolerance_m of an occupied reference cell's centre, and
//     occupied recall the converse. A wall drawn twice, or in the wrong place, lowers precision
//     without changing recall, which a class-by-class agreement would mostly hide in the many
//     free cells; the tolerance forgives a wall one cell off, as rasterising the same wall from
//     slightly different poses gives.
// A fraction without anything to count (no cell known in both, no occupied cell in the estimate
// or in the reference) is std::nullopt, never NaN or a division by zero; its counts are then 0.

#include <cstddef>
#include <optional>

#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::robot {

struct MapComparisonOptions {
  /// [m] how far an occupied cell's centre may be from the other grid's nearest occupied centre
  /// and still count as matched; unset: one cell of the coarser grid (max of the resolutions).
  /// A centre exactly at the tolerance matches (squared distances are compared with a slack of
  /// 1e-9 of the larger of tolerance^2 and the other grid's cell area, for rounding).
  std::optional<double> tolerance_m;

  /// Throws InvalidArgument naming tolerance_m when it is set and negative, NaN or infinite.
  void validate() const;
};

struct MapComparison {
  double tolerance_m = 0.0;  ///< [m] the tolerance used
  // Agreement, at the reference's cell centres.
  std::size_t known_in_both = 0;  ///< reference cells known (occupied or free) in both grids
  std::size_t both_occupied = 0;  ///< of them, occupied in both
  std::size_t both_free = 0;      ///< of them, free in both
  /// (both_occupied + both_free) / known_in_both; nullopt when known_in_both is 0.
  std::optional<double> agreement;
  // Occupied cells matched within the tolerance, each grid's own cells.
  std::size_t estimate_occupied = 0, estimate_occupied_matched = 0;
  std::size_t reference_occupied = 0, reference_occupied_matched = 0;
  /// estimate_occupied_matched / estimate_occupied; nullopt when estimate_occupied is 0.
  std::optional<double> occupied_precision;
  /// reference_occupied_matched / reference_occupied; nullopt when reference_occupied is 0.
  std::optional<double> occupied_recall;
  /// 2 P R / (P + R), 0 when P = R = 0; nullopt when either is.
  std::optional<double> occupied_f1;
};

/// The estimate against the reference (see the file comment). Costs one look-up per reference
/// cell plus, per occupied cell of either grid, a look at the other grid's cells within the
/// tolerance: at most (2 tolerance / resolution + 3)^2 of them (25 at the default, equal
/// resolutions). Throws InvalidArgument for an empty grid (naming which) or invalid options.
MapComparison compare_maps(const OccupancyGrid& estimate, const OccupancyGrid& reference,
                           const MapComparisonOptions& options = {});

}  // namespace implicit::robot
