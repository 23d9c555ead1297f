#pragma once
// The scan's log-likelihood against a particle's OWN map (spec §3.13.1): what the three proposals
// of grid SLAM (grid_proposals.hpp) weight by, and what the scan-matched and implicit proposals
// minimise. Each used beam i ends, at robot pose x = (t, theta), at p_i(x) = t + R(theta) e_i
// (e_i its end point in the robot frame, mount included), and
//
//   log p(scan | x, map) = sum_i log( eps + (1 - eps) M(p_i(x)) )
//
// with M the cells' occupancy evidence O = max(0, 2P - 1) (P the occupancy probability; 0 in
// free and unknown space alike; 1 in a cell with the map's min_echoes echoes) smoothed by a
// cubic B-spline kernel of `smoothing` cells (Hector SLAM's interpolated map, with a wider
// basin; a convex combination of cells, so 0 <= M <= 1) and eps the mixture floor: an end point
// in free or unknown space costs -log eps, never -inf. Beams with no return are left out, and at
// most max_beams hits are used, evenly spaced over the scan's hits.
//
//   slam::GridScanModel model(particle_map, params, mount);
//   slam::ScanMatchBeams beams = model.prepare(scan, "scan 12");   // once per scan, shared
//   double lp = model.log_likelihood(beams, x);
//   double f = model.negative_log_likelihood(beams, x, &g, &h, &gn);  // adds to g, h, gn
//
// The model holds a pointer to the map (and a copy of the params): a view, built per particle
// per step (no allocation), that must not outlive the map.

#include <string_view>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/types.hpp"
#include "implicit/slam/grid/tiled_grid.hpp"

namespace implicit::slam {

struct ScanMatchParams {
  int max_beams = 60;      ///< hits used per scan, evenly spaced over the scan's hits
  double floor = 0.1;      ///< eps: the mixture floor of a beam's likelihood, in (0, 1)
  int smoothing = 2;       ///< [cells] scale of the B-spline kernel, 1..kMaxSmoothing
  double max_range = 0.0;  ///< [m] beams at or beyond are not used; <= 0: the scan's range_max

  static constexpr int kMaxSmoothing = 4;
  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// A scan's used beams: end points in the robot frame [m]. Computed once per scan.
struct ScanMatchBeams {
  std::vector<Vec<2>> end_points;
  std::size_t size() const { return end_points.size(); }
};

class GridScanModel {
 public:
  using Observation = robot::LaserScan;
  using Prepared = ScanMatchBeams;

  /// A view of `map` (not owned). Throws InvalidArgument for invalid params or a non-finite mount.
  GridScanModel(const TiledLogOddsGrid& map, const ScanMatchParams& params,
                const robot::LaserMount& mount = {});
  /// The same without validating (params checked once by the caller): the per-particle path.
  static GridScanModel unchecked(const TiledLogOddsGrid& map, const ScanMatchParams& params,
                                 const robot::LaserMount& mount);

  const ScanMatchParams& params() const { return params_; }
  const TiledLogOddsGrid& map() const { return *map_; }
  const robot::LaserMount& mount() const { return mount_; }

  /// The beams used of `scan` (validated; `where` names it in errors). A scan without a hit
  /// gives no beams: its likelihood is 1.
  ScanMatchBeams prepare(const robot::LaserScan& scan, std::string_view where = "laser scan") const;
  /// The same into `out`, reusing its storage.
  void prepare_into(const robot::LaserScan& scan, std::string_view where,
                    ScanMatchBeams& out) const;

  double log_likelihood(const ScanMatchBeams& z, const robot::Pose& x) const {
    return -negative_log_likelihood(z, x, nullptr, nullptr, nullptr);
  }
  bool differentiable() const { return true; }
  std::string_view why_not_differentiable() const { return ""; }

  /// -log p(scan | x, map); ADDS to each non-null output its gradient, exact Hessian and a
  /// positive semi-definite Gauss-Newton matrix (the outer-product part of the Hessian).
  double negative_log_likelihood(const ScanMatchBeams& z, const robot::Pose& x, Vec<3>* gradient,
                                 robot::Mat3* hessian, robot::Mat3* gauss_newton) const;
  /// The observation-model form (robot/observation_model.hpp): gradient and Gauss-Newton only.
  double negative_log_likelihood(const ScanMatchBeams& z, const robot::Pose& x, Vec<3>* gradient,
                                 robot::Mat3* gauss_newton) const {
    return negative_log_likelihood(z, x, gradient, nullptr, gauss_newton);
  }

  /// M(p), the smoothed occupancy evidence at world point p, with its gradient and Hessian in p
  /// when asked.
  double smoothed_occupancy(const Vec<2>& p, Vec<2>* gradient = nullptr,
                            robot::Mat2* hessian = nullptr) const;

 private:
  GridScanModel() = default;
  const TiledLogOddsGrid* map_ = nullptr;
  ScanMatchParams params_;
  robot::LaserMount mount_;
};

}  // namespace implicit::slam
