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
//   LandmarkGridIndex index;                  // shared by all particles of a filter
//   index.insert(slot, mean, cov.trace());    // whenever any particle writes landmark `slot`
//   auto a = associate_indexed(map, index, sensor, f, sigma1, z, gate, scratch);
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
// Covariance classes: the disc grows with the landmark covariance, and a few far, rarely seen
// landmarks (at 50 m range a new landmark has a lateral variance of 2 m^2) would inflate it for
// all. So landmarks are bucketed by the trace of their covariance into classes c with
// trace <= kClassTrace0 * 4^c, each class on its own grid with cells 2^c times larger; a query
// visits every class with that class's disc, a few cells each.
//
// Mistakes to avoid: forgetting to insert after an EKF update moved a landmark into another cell
// or covariance class (the indexed association would then miss it).

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
  static constexpr double kDefaultCellSize = 4.0;  ///< [m] of class 0, about its search radius
  static constexpr double kClassTrace0 = 0.25;     ///< [m^2] largest covariance trace of class 0
  static constexpr int kMaxClass = 24;

  /// Throws InvalidArgument unless cell_size > 0 and finite.
  explicit LandmarkGridIndex(double cell_size = kDefaultCellSize);

  double cell_size() const { return cell_size_; }
  /// Covariance class of a landmark whose covariance has this trace.
  static int covariance_class(double cov_trace);
  /// Largest covariance trace of class c.
  static double class_trace(int c);
  /// Registers `slot` in the cell of `position` of the class of cov_trace (no-op when already
  /// there). Non-finite positions are ignored (such a landmark can never pass the gate).
  void insert(std::uint32_t slot, const Vec<2>& position, double cov_trace);
  /// True when (a, trace_a) and (b, trace_b) fall into the same class and cell.
  bool same_bucket(const Vec<2>& a, double trace_a, const Vec<2>& b, double trace_b) const;
  /// Largest class holding an entry (-1 when empty).
  int max_class() const { return max_class_; }
  /// Whether class c holds an entry.
  bool has_class(int c) const { return c >= 0 && c <= kMaxClass && class_used_[c]; }
  /// Number of cells of class c meeting the bounding square of the disc (huge for huge radii).
  double cells_covering(int c, const Vec<2>& center, double radius) const;
  /// Appends the slots registered in the cells of class c meeting the bounding square of the
  /// disc (center, radius); not sorted, may repeat.
  void query(int c, const Vec<2>& center, double radius, std::vector<std::uint32_t>& out) const;
  /// Registered (cell, slot) entries.
  std::size_t entries() const { return entries_; }
  std::size_t cells() const { return cells_.size(); }
  void clear();

 private:
  std::int64_t cell_coordinate(int c, double v) const;
  static std::uint64_t key(int c, std::int64_t cx, std::int64_t cy);

  double cell_size_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
  std::size_t entries_ = 0;
  int max_class_ = -1;
  bool class_used_[kMaxClass + 1] = {};
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
robot::Association associate_scan(const LandmarkEstimates& map,
                                  const robot::RangeBearingSensor& sensor, const Pose& f,
                                  const Mat<3>& sigma1, const Measurement& z, double gate,
                                  double cov_trace_bound = -1.0);

/// The same association through the index: scores only the candidates the index returns (in
/// slot order, so ties resolve as in the scan). Falls back to the scan when the discs cover more
/// cells than the map has landmarks. `scratch` avoids an allocation per call.
robot::Association associate_indexed(const LandmarkEstimates& map, const LandmarkGridIndex& index,
                                     const robot::RangeBearingSensor& sensor, const Pose& f,
                                     const Mat<3>& sigma1, const Measurement& z, double gate,
                                     std::vector<std::uint32_t>& scratch);

}  // namespace implicit::slam
