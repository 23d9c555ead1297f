#pragma once
// The heaviest cluster of a weighted cloud of planar poses, and its weighted mean: the pose a
// localization filter reports when its posterior has several modes.
//
// The weighted mean of a cloud split between two places lies between them, where no particle is;
// AMCL (and nav2, Beluga) report instead the mean of the cluster that carries the most weight. The
// clusters here are the connected groups of occupied cells of a grid over (x, y, heading) — cells
// of `cell_m` metres and `cell_rad` radians, neighbours in all 26 directions, heading wrapping
// round — the same rule as AMCL's k-d tree clustering on its histogram.
//
//   const PoseCluster c = heaviest_cluster(pf.particles(), pf.weights());
//   report(c.mean);
//
// Deterministic: cells and clusters are numbered in particle order, and a tie in weight goes to
// the cluster numbered first, so the result does not depend on how the cloud was computed.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <unordered_map>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::filter {

struct PoseCluster {
  robot::Pose mean = robot::Pose::Zero();  ///< weighted mean (heading: of the unit vectors)
  double weight = 0.0;                     ///< share of the cloud's weight in the cluster
  std::size_t particles = 0;
  std::size_t clusters = 0;  ///< how many clusters the cloud has
};

struct ClusterOptions {
  double cell_m = 0.5;           ///< [m] AMCL's pf's histogram cell
  double cell_rad = kPi / 18.0;  ///< [rad] 10 degrees
};

namespace detail {

/// Union-find over cell indices, with path halving.
inline std::size_t cluster_root(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline std::uint64_t cell_key(std::int64_t ix, std::int64_t iy, std::int64_t ih) {
  // 24 bits per coordinate (offset to unsigned): cells of 0.5 m reach 2000 km either way.
  constexpr std::int64_t kOffset = std::int64_t{1} << 23;
  constexpr std::uint64_t kMask = (std::uint64_t{1} << 24) - 1;
  return ((static_cast<std::uint64_t>(ix + kOffset) & kMask) << 40) |
         ((static_cast<std::uint64_t>(iy + kOffset) & kMask) << 16) |
         (static_cast<std::uint64_t>(ih) & 0xffff);
}

}  // namespace detail

/// The heaviest cluster of the cloud (weights need not be normalised). Throws InvalidArgument
/// when the spans differ in length or are empty, a cell size is not positive, a weight is
/// negative or not finite, the total weight is zero, or a pose is not finite.
inline PoseCluster heaviest_cluster(std::span<const robot::Pose> xs, std::span<const double> w,
                                    const ClusterOptions& o = {}) {
  require(!xs.empty() && xs.size() == w.size(),
          "heaviest_cluster: expected one weight per pose and at least one pose, got {} poses and "
          "{} weights",
          xs.size(), w.size());
  require(o.cell_m > 0 && std::isfinite(o.cell_m) && o.cell_rad > 0 && o.cell_rad <= kPi,
          "heaviest_cluster: expected cells of positive size (at most pi in heading), got {} m and "
          "{} rad",
          o.cell_m, o.cell_rad);
  // The last heading cell is narrower when cell_rad does not divide a turn; the 1e-9 keeps a cell
  // that does (10 degrees) from gaining a sliver cell through rounding.
  const auto headings = static_cast<std::int64_t>(std::ceil(2.0 * kPi / o.cell_rad - 1e-9));
  // The cell key holds 24 bits per coordinate.
  const double reach = o.cell_m * static_cast<double>(std::int64_t{1} << 22);
  // Each particle's cell, numbered in order of first appearance.
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<std::size_t> cell_of(xs.size());
  std::vector<std::array<std::int64_t, 3>> cells;
  double total = 0.0;
  for (std::size_t j = 0; j < xs.size(); ++j) {
    require(w[j] >= 0 && std::isfinite(w[j]),
            "heaviest_cluster: weight {} is {} (expected finite and non-negative)", j, w[j]);
    require(xs[j].allFinite(), "heaviest_cluster: pose {} is not finite", j);
    require(std::abs(xs[j](0)) < reach && std::abs(xs[j](1)) < reach,
            "heaviest_cluster: pose {} is outside +-{} m (cells of {} m)", j, reach, o.cell_m);
    total += w[j];
    const std::int64_t ix = static_cast<std::int64_t>(std::floor(xs[j](0) / o.cell_m));
    const std::int64_t iy = static_cast<std::int64_t>(std::floor(xs[j](1) / o.cell_m));
    const double h = wrap_angle(xs[j](2)) + kPi;  // in [0, 2 pi]
    const std::int64_t ih = static_cast<std::int64_t>(std::floor(h / o.cell_rad)) % headings;
    const auto [it, added] = index.try_emplace(detail::cell_key(ix, iy, ih), cells.size());
    if (added) cells.push_back({ix, iy, ih});
    cell_of[j] = it->second;
  }
  require(total > 0, "heaviest_cluster: every weight is zero");
  // Join each occupied cell with its occupied neighbours.
  std::vector<std::size_t> parent(cells.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dh = -1; dh <= 1; ++dh) {
          const std::int64_t h = (cells[c][2] + dh + headings) % headings;
          const auto it = index.find(detail::cell_key(cells[c][0] + dx, cells[c][1] + dy, h));
          if (it == index.end()) continue;
          const std::size_t a = detail::cluster_root(parent, c);
          const std::size_t b = detail::cluster_root(parent, it->second);
          // The smaller index is the root: clusters are numbered by their first cell.
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
  std::vector<double> weight(cells.size(), 0.0);
  for (std::size_t j = 0; j < xs.size(); ++j)
    weight[detail::cluster_root(parent, cell_of[j])] += w[j];
  PoseCluster out;
  std::size_t best = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (detail::cluster_root(parent, c) != c) continue;
    ++out.clusters;
    if (weight[c] > weight[best]) best = c;
  }
  // The cluster's weighted mean; the heading as the direction of the mean unit vector.
  double sw = 0.0, sx = 0.0, sy = 0.0, sc = 0.0, ss = 0.0;
  for (std::size_t j = 0; j < xs.size(); ++j) {
    if (detail::cluster_root(parent, cell_of[j]) != best) continue;
    ++out.particles;
    sw += w[j];
    sx += w[j] * xs[j](0);
    sy += w[j] * xs[j](1);
    sc += w[j] * std::cos(xs[j](2));
    ss += w[j] * std::sin(xs[j](2));
  }
  // sw > 0: the heaviest cluster carries at least total / clusters.
  out.weight = sw / total;
  out.mean = robot::Pose(sx / sw, sy / sw, std::atan2(ss, sc));
  return out;
}

}  // namespace implicit::filter
