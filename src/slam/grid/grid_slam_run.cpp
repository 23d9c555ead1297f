#include "implicit/slam/grid/grid_slam_run.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <optional>
#include <string>
#include <utility>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/grid_mapping.hpp"

namespace implicit::slam {

std::string_view to_string(GridProposalKind kind) {
  switch (kind) {
    case GridProposalKind::kBootstrap:
      return "bootstrap";
    case GridProposalKind::kScanMatch:
      return "gmapping";
    case GridProposalKind::kImplicit:
      return "implicit";
  }
  return "?";
}

GridProposalKind parse_grid_proposal(std::string_view name) {
  for (GridProposalKind k :
       {GridProposalKind::kBootstrap, GridProposalKind::kScanMatch, GridProposalKind::kImplicit})
    if (name == to_string(k)) return k;
  throw InvalidArgument("grid SLAM proposal: expected bootstrap, gmapping or implicit, got '" +
                        std::string(name) + "'");
}

std::shared_ptr<const GridProposal> make_grid_proposal(GridProposalKind kind,
                                                       const ImplicitGridOptions& implicit,
                                                       const ScanMatchProposalOptions& scan_match) {
  switch (kind) {
    case GridProposalKind::kBootstrap:
      return std::make_shared<BootstrapGridProposal>();
    case GridProposalKind::kScanMatch:
      return std::make_shared<ScanMatchGridProposal>(scan_match);
    case GridProposalKind::kImplicit:
      return std::make_shared<ImplicitGridProposal>(implicit);
  }
  throw InvalidArgument("grid SLAM proposal: unknown kind");
}

void GridSlamRunOptions::validate() const {
  filter.validate();
  implicit.validate();
  scan_match.validate();
  map_comparison.validate();
}

namespace {

double cpu_seconds_since(std::clock_t start) {
  return static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
}

// The map scores of spec §3.13.5: the reference map and the dead-reckoning map are built from the
// processed scans with the filter's mount and mapping options, so that their cells line up with
// the filter's (corners on multiples of the resolution) and a filter with every pose right would
// reproduce the reference cell by cell. Cost: each map is one particle's mapping work over the
// run (the filter does that work for every particle, and matches scans besides), plus a pass over
// the cells per comparison; score_map = false skips it all.
void score_maps(const robot::CarmenLog& log, const std::vector<std::size_t>& used,
                const std::vector<robot::Pose>& odometry, const GridSlamRunOptions& options,
                GridSlamRun& run) {
  const std::clock_t start = std::clock();
  std::vector<robot::LaserScan> scans;
  std::vector<robot::Pose> reference;
  for (std::size_t k : used) {
    scans.push_back(log.scans[k]);
    reference.push_back(log.laser_poses[k]);
  }
  const robot::OccupancyGrid truth =
      robot::build_map(reference, scans, options.filter.mount, options.filter.map);
  run.reference_map_cpu_seconds = cpu_seconds_since(start);
  run.map_score = robot::compare_maps(run.map, truth, options.map_comparison);
  const robot::OccupancyGrid dead_reckoning =
      robot::build_map(odometry, scans, options.filter.mount, options.filter.map);
  run.odometry_map_score = robot::compare_maps(dead_reckoning, truth, options.map_comparison);
  run.map_score_cpu_seconds = cpu_seconds_since(start);
}

/// The RMSE of `est`'s positions against `ref`'s after the SE(2) alignment of est onto ref
/// (pairs by index); nullopt when fewer than two poses or every estimated position is the same,
/// where no rotation is fixed.
std::optional<double> aligned_rmse(const std::vector<robot::Pose>& est,
                                   const std::vector<GridSlamPose>& ref) {
  if (est.size() < 2 || est.size() != ref.size()) return std::nullopt;
  const bool moved = std::any_of(est.begin(), est.end(), [&](const robot::Pose& p) {
    return p.head<2>() != est.front().head<2>();
  });
  if (!moved) return std::nullopt;
  robot::PosePairs pairs;
  for (std::size_t i = 0; i < est.size(); ++i) {
    pairs.times.push_back(static_cast<double>(i));
    pairs.ref.push_back(robot::Pose3::from_se2(ref[i].pose));
    pairs.est.push_back(robot::Pose3::from_se2(est[i]));
    pairs.ref_index.push_back(i);
    pairs.est_index.push_back(i);
  }
  const robot::TrajectoryErrors e =
      robot::absolute_pose_error(pairs, robot::align_umeyama(pairs, robot::AlignmentKind::kSe2));
  double ss = 0.0;
  for (double t : e.translation) ss += t * t;
  return std::sqrt(ss / static_cast<double>(e.translation.size()));
}

}  // namespace

GridSlamRun run_grid_slam(const robot::CarmenLog& log, const GridSlamRunOptions& options) {
  options.validate();
  require(!log.scans.empty() && log.scans.size() == log.laser_poses.size(),
          "run_grid_slam: {}: expected laser scans with their poses, got {} scans and {} poses",
          log.source, log.scans.size(), log.laser_poses.size());
  const std::size_t n =
      options.max_scans > 0 ? std::min(options.max_scans, log.scans.size()) : log.scans.size();
  // The protocol's updates: where the reference moved or turned by the gate since the last one;
  // the odometry between them is the reference increment perturbed by the alphas. Recorded
  // odometry is gated and used as it is (GMapping gates on odometry too).
  const bool recorded = options.odometry == GridOdometrySource::kRecorded;
  std::vector<std::size_t> used{0};
  for (std::size_t k = 1; k < n; ++k)
    if (options.filter.gate.due(log.laser_poses[used.back()], log.laser_poses[k]))
      used.push_back(k);
  std::vector<robot::Pose> odometry{log.laser_poses[0]};
  for (std::size_t i = 1; i < used.size(); ++i) {
    if (recorded) {
      odometry.push_back(log.laser_poses[used[i]]);
      continue;
    }
    Rng rng({.seed = options.data_seed, .step = i, .purpose = purpose::kData});
    const robot::Pose inc = robot::between(log.laser_poses[used[i - 1]], log.laser_poses[used[i]]);
    odometry.push_back(
        robot::compose(odometry.back(), robot::perturb_odometry(inc, options.filter.alphas, rng)));
  }
  GridSlamOptions fo = options.filter;
  fo.gate = MapUpdateGate{0.0, 0.0};  // the protocol chose the scans
  GridSlam filter(fo, make_grid_proposal(options.proposal, options.implicit, options.scan_match));
  GridSlamRun run;
  const std::clock_t start = std::clock();
  filter.initialize(log.laser_poses[0], odometry[0], log.scans[0]);
  double ess = 0.0, evaluations = 0.0;
  for (std::size_t i = 1; i < used.size(); ++i) {
    const GridSlamStep s = filter.step(odometry[i], log.scans[used[i]]);
    ess += s.ess / static_cast<double>(fo.particles);
    evaluations += s.mean_evaluations;
    run.resamplings += s.resampled;
    run.fallbacks += static_cast<std::size_t>(s.fallbacks);
    run.failures += static_cast<std::size_t>(s.failures);
    if (options.on_step) options.on_step(i + 1, used.size());
  }
  run.cpu_seconds = cpu_seconds_since(start);
  run.processed = used.size();
  const double steps = std::max<double>(1.0, static_cast<double>(used.size() - 1));
  run.mean_ess = ess / steps;
  run.mean_evaluations = evaluations / steps;
  run.trajectory = filter.best_trajectory();
  run.map = filter.best_map().to_occupancy_grid();
  if (recorded) {
    run.has_reference = false;
    run.odometry = std::move(odometry);
    return run;
  }
  for (std::size_t k : used) run.reference.push_back({log.scans[k].time, log.laser_poses[k]});
  // Relations between consecutive processed scans, matched by their index (the bundled logs'
  // scan times are not always increasing: Intel's go back by 0.11 s once).
  std::vector<double> times;
  std::vector<robot::Pose> poses;
  std::vector<robot::Relation> relations;
  for (std::size_t i = 0; i < run.trajectory.size(); ++i) {
    times.push_back(static_cast<double>(i));
    poses.push_back(run.trajectory[i].pose);
    if (i == 0) continue;
    robot::Relation r;
    r.t1 = static_cast<double>(i - 1);
    r.t2 = static_cast<double>(i);
    r.delta = robot::Pose3::from_se2(run.reference[i - 1].pose).inverse() *
              robot::Pose3::from_se2(run.reference[i].pose);
    relations.push_back(r);
  }
  if (!relations.empty()) {
    run.relations = robot::relation_errors(robot::Trajectory::from_se2(times, poses), relations,
                                           {.max_diff = 0.1});
    run.odometry_relations = robot::relation_errors(robot::Trajectory::from_se2(times, odometry),
                                                    relations, {.max_diff = 0.1});
  }
  run.ate_m = aligned_rmse(poses, run.reference);
  run.odometry_ate_m = aligned_rmse(odometry, run.reference);
  if (options.score_map) score_maps(log, used, odometry, options, run);
  run.odometry = std::move(odometry);
  return run;
}

}  // namespace implicit::slam
