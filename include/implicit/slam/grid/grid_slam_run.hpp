#pragma once
// Grid SLAM over a whole CARMEN log by the semi-synthetic protocol (data/carmen/README.md): the
// real scans, odometry synthesised from the corrected poses' increments with the odometry
// model's noise, and the corrected poses as the reference (spec §3.13.4).
//
//   robot::CarmenLog log = robot::read_carmen("data/carmen/intel-corrected.log.gz");
//   slam::GridSlamRunOptions o;                 // implicit proposal, 8 particles
//   o.proposal = slam::GridProposalKind::kScanMatch;
//   slam::GridSlamRun run = slam::run_grid_slam(log, o);
//   run.relations.translation_mean;             // [m] against the corrected poses
//   robot::OccupancyGrid map = run.map;         // the best particle's
//   run.map_score->occupied_f1;                 // against the corrected poses' map (§3.13.5)

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "implicit/robot/carmen.hpp"
#include "implicit/robot/map_comparison.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/trajectory_metrics.hpp"
#include "implicit/slam/grid/grid_slam.hpp"

namespace implicit::slam {

enum class GridProposalKind { kBootstrap, kScanMatch, kImplicit };
std::string_view to_string(GridProposalKind kind);
/// "bootstrap", "gmapping" or "implicit"; throws InvalidArgument otherwise.
GridProposalKind parse_grid_proposal(std::string_view name);
/// The proposal of that kind with the given options (the other kinds' are not used).
std::shared_ptr<const GridProposal> make_grid_proposal(
    GridProposalKind kind, const ImplicitGridOptions& implicit = {},
    const ScanMatchProposalOptions& scan_match = {});

/// Where the filter's odometry comes from.
enum class GridOdometrySource {
  /// The semi-synthetic protocol: the log's laser poses are the reference, and the odometry is
  /// their increments perturbed by the alphas.
  kSynthesised,
  /// The log's laser poses are the robot's own odometry (a ROS bag's, robot/bag.hpp), used as
  /// recorded: the run has no reference, so no score that needs one (relations, ATE, map).
  kRecorded,
};

struct GridSlamRunOptions {
  /// The filter; its gate is the protocol's (applied to the reference poses) and its alphas
  /// both synthesise the odometry and drive the motion model.
  /// Alphas 0.002: per metre driven, 4.5 cm of translation and 2.6 degrees of heading noise.
  GridSlamOptions filter = [] {
    GridSlamOptions o;
    o.particles = 8;
    o.alphas = {0.002, 0.002, 0.002, 0.002};
    return o;
  }();
  GridProposalKind proposal = GridProposalKind::kImplicit;
  ImplicitGridOptions implicit;
  ScanMatchProposalOptions scan_match;
  GridOdometrySource odometry = GridOdometrySource::kSynthesised;
  std::uint64_t data_seed = 1;  ///< the odometry's noise: stream (data_seed, scan, 0, data)
  std::size_t max_scans = 0;    ///< 0: every scan of the log; else the first max_scans
  /// Score the best particle's map, and the dead-reckoning map, against the reference map
  /// (spec §3.13.5); false skips building the two maps.
  bool score_map = true;
  robot::MapComparisonOptions map_comparison;  ///< its tolerance (default one cell)
  /// Called after each processed scan with (scans done, scans to process): progress.
  std::function<void(std::size_t, std::size_t)> on_step;
  void validate() const;
};

struct GridSlamRun {
  std::vector<GridSlamPose> trajectory;  ///< the best particle's, at the processed scans
  /// The corrected poses at the same scans; empty with recorded odometry (no reference).
  std::vector<GridSlamPose> reference;
  /// The odometry the filter was given at the same scans (its motion input): the increments of
  /// the pose graph (robot/pose_graph.hpp).
  std::vector<robot::Pose> odometry;
  robot::OccupancyGrid map;  ///< the best particle's map
  /// Kümmerle et al.'s relation metric over consecutive processed scans, the reference's
  /// relative motions as the relations.
  robot::RelationErrors relations;
  /// False with recorded odometry: the relation errors are then empty (not zero errors), and
  /// ate_m and the map scores nullopt.
  bool has_reference = true;
  /// The same for the synthesised odometry itself (dead reckoning): what the scans improve on.
  robot::RelationErrors odometry_relations;
  /// Absolute trajectory error [m]: the RMSE of the best trajectory's positions against the
  /// reference's at the processed scans after the least-squares SE(2) alignment of the
  /// estimate onto the reference (Umeyama; spec §3.13.4). nullopt when the positions cannot fix
  /// the alignment (fewer than two scans processed, or no motion).
  std::optional<double> ate_m;
  std::optional<double> odometry_ate_m;  ///< the same for the synthesised odometry
  /// The best particle's map against the reference map: robot::build_map of the processed scans
  /// at their reference poses, with the filter's mount and mapping options, so that a filter
  /// with every pose right would score 1 throughout (spec §3.13.5). nullopt when not asked for.
  std::optional<robot::MapComparison> map_score;
  /// The map of the processed scans at the synthesised odometry's poses, scored the same way.
  std::optional<robot::MapComparison> odometry_map_score;
  double reference_map_cpu_seconds = 0.0;  ///< process CPU time of building the reference map
  double map_score_cpu_seconds = 0.0;      ///< of both maps and both comparisons
  std::size_t processed = 0;               ///< scans processed (the first included)
  std::size_t resamplings = 0;
  double mean_ess = 0.0;          ///< N_eff / N before resampling, over the steps
  double mean_evaluations = 0.0;  ///< scan-likelihood evaluations per particle and step
  std::size_t fallbacks = 0, failures = 0;
  double cpu_seconds = 0.0;  ///< process CPU time of the filter (not the set-up)
};

/// Throws InvalidArgument for invalid options or a log without scans.
GridSlamRun run_grid_slam(const robot::CarmenLog& log, const GridSlamRunOptions& options);

}  // namespace implicit::slam
