#pragma once
// Maximum-likelihood association of one detection against a particle's landmark map, by a linear
// scan or through a spatial grid index whose cost does not grow with the map size.
//
// A particle scores every landmark k of its map by cost_k = d_k^2 + log det S_k with
//   S_k = H_x Sigma1 H_x^T + H_m P_k H_m^T + Sigma2   (at the predicted pose f),
// keeps those inside the chi-square gate d_k^2 <= gate and picks the cheapest (robot/
// data_association.hpp). A linear scan costs O(N) per particle and detection. The gate, however,
// confines every admissible landmark to a disc around the point where the detection lands when
// seen from f: association_search_radius() derives that disc from upper bounds on S (see the .cpp),
// so only the landmarks registered in the grid cells that meet it need scoring.
//
//   LandmarkGridIndex index;                       // shared by all particles of a filter
//   index.insert(slot, mean);                      // whenever any particle writes landmark `slot`
//   auto a = associate_indexed(map, index, cov_trace_bound, sensor, f, sigma1, z, gate, scratch);
//   // a == associate_scan(map, sensor, f, sigma1, z, gate), bit for bit, for every map
//
// Why one index for all particles: particles share landmark storage copy-on-write and mostly the
// same slots, so a per-particle index would have to be persistent too. The shared grid keeps, per
// cell, every slot that ANY particle ever placed there (insert-only): for each particle and slot
// the cell of its current mean is registered, so a query returns a superset of that particle's
// landmarks near the detection, and the exact scoring of each candidate (against the particle's
// own landmark) removes the rest. Landmarks that move with EKF updates are registered again in
// the new cell; stale entries only cost a look-up.
//
// Mistakes to avoid: forgetting to insert after an EKF update moved a landmark into another cell
// (the indexed association would then miss it), and using a cov_trace_bound below the trace of a
// landmark covariance in the map (the search disc would be too small). The EKF update never
// increases a covariance, so the largest trace at creation bounds it for good.

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/data_association.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/slam/landmark_map.hpp"

namespace implicit::slam {

using robot::Measurement;
using robot::Pose;

/// Uniform grid over the plane; each cell lists the landmark slots registered in it.
class LandmarkGridIndex {
 public:
  static constexpr double kDefaultCellSize = 4.0;  ///< [m], about the search radius at 8 m range

  /// Throws InvalidArgument unless cell_size > 0 and finite.
  explicit LandmarkGridIndex(double cell_size = kDefaultCellSize);

  double cell_size() const { return cell_size_; }
  /// Registers `slot` in the cell of `position` (no-op when already there). Non-finite positions
  /// are ignored (such a landmark can never pass the gate).
  void insert(std::uint32_t slot, const Vec<2>& position);
  /// True when a and b fall into the same cell.
  bool same_cell(const Vec<2>& a, const Vec<2>& b) const;
  /// Number of cells meeting the bounding square of the disc (huge for huge radii).
  double cells_covering(const Vec<2>& center, double radius) const;
  /// Replaces `out` by the sorted, duplicate-free slots registered in the cells meeting the
  /// bounding square of the disc (center, radius).
  void query(const Vec<2>& center, double radius, std::vector<std::uint32_t>& out) const;
  /// Registered (cell, slot) entries.
  std::size_t entries() const { return entries_; }
  std::size_t cells() const { return cells_.size(); }
  void clear();

 private:
  std::int64_t cell_coordinate(double v) const;
  static std::uint64_t key(std::int64_t cx, std::int64_t cy);

  double cell_size_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
  std::size_t entries_ = 0;
};

/// The disc that contains every landmark able to pass the gate.
struct SearchDisc {
  Vec<2> center = Vec<2>::Zero();
  double radius = 0.0;        ///< +inf when no bound applies
  double range_margin = 0.0;  ///< |range(f, m) - z_r| <= range_margin for every admissible m
};

/// Conservative search disc for a detection z seen from the predicted pose f with covariance
/// sigma1, against landmarks whose covariance traces are at most cov_trace_bound.
SearchDisc association_search_disc(const robot::RangeBearingSensor& sensor, const Pose& f,
                                   const Mat<3>& sigma1, const Measurement& z,
                                   double cov_trace_bound, double gate);

/// The reference rule: scores every landmark of the map in slot order. A cheap range check
/// skips landmarks that cannot pass the gate; it needs a bound on the traces of the landmark
/// covariances (negative: computed from the map, one extra pass).
robot::Association associate_scan(const LandmarkMap& map, const robot::RangeBearingSensor& sensor,
                                  const Pose& f, const Mat<3>& sigma1, const Measurement& z,
                                  double gate, double cov_trace_bound = -1.0);

/// The same association through the index: scores only the candidates the index returns (in
/// slot order, so ties resolve as in the scan). Falls back to the scan when the disc covers more
/// cells than the map has landmarks. `scratch` avoids an allocation per call.
robot::Association associate_indexed(const LandmarkMap& map, const LandmarkGridIndex& index,
                                     double cov_trace_bound,
                                     const robot::RangeBearingSensor& sensor, const Pose& f,
                                     const Mat<3>& sigma1, const Measurement& z, double gate,
                                     std::vector<std::uint32_t>& scratch);

}  // namespace implicit::slam
