#pragma once
// Grid SLAM: a Rao-Blackwellized particle filter whose particles each carry a pose and their own
// occupancy grid (spec §3.13), on the one particle engine (filter/particle_engine.hpp), with the
// proposal a plug-in (grid_proposals.hpp: bootstrap, GMapping-style scan matching, implicit).
//
//   slam::GridSlamOptions o;                                 // 30 particles, 5 cm cells, ...
//   slam::GridSlam filter(o, std::make_shared<slam::ImplicitGridProposal>());
//   filter.initialize(x0, odometry[0], scans[0]);            // every particle maps scan 0 at x0
//   for (k = 1..) filter.step(odometry[k], scans[k]);        // odometry: the robot's pose
//   robot::OccupancyGrid map = filter.best_map().to_occupancy_grid();
//   std::vector<slam::GridSlamPose> path = filter.best_trajectory();
//
// A step whose odometry has not moved the robot by the MapUpdateGate's distance or turn since the
// last processed scan is skipped (GMapping's linearUpdate / angularUpdate); otherwise, with u the
// odometry increment since then:
//   1. every particle draws its pose from the proposal, against its own map, and gets its log
//      weight increment (in parallel; particle j draws from the stream (seed, step, j, proposal));
//   2. the weights are normalised; when N_eff < resample_threshold * N the particles are
//      resampled (systematic; copies share their map tiles, filter/ and tiled_grid.hpp);
//   3. every particle integrates the scan into its map at its new pose.
// The results are the same for any number of threads. Each particle's trajectory is kept as a
// node in a tree shared by all particles (its parent the pose it came from), appended per step
// without an allocation per particle.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "implicit/filter/particle_engine.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/types.hpp"
#include "implicit/slam/grid/grid_proposals.hpp"
#include "implicit/slam/grid/map_update_gate.hpp"
#include "implicit/slam/grid/scan_match.hpp"
#include "implicit/slam/grid/tiled_grid.hpp"

namespace implicit::slam {

struct GridSlamOptions {
  std::size_t particles = 30;
  std::uint64_t seed = 1;
  double resample_threshold = 0.5;  ///< resample when N_eff < this * particles; in [0, 1]
  /// The particles' maps and the reference map of the map score (the same options, so a filter
  /// with every pose right draws the reference). min_echoes = 1: a cell where any scan's beam
  /// ended stays occupied evidence for the scan match, however many beams cross it later. Beams
  /// that graze a wall cross its cells before they end, and in log-odds alone the corridors
  /// of Intel lost the walls the next scan has to match (spec §3.13.1, "Echoes").
  robot::GridMappingOptions map = [] {
    robot::GridMappingOptions m;
    m.max_range = 40.0;
    m.min_echoes = 1;
    return m;
  }();
  ScanMatchParams scan;
  MapUpdateGate gate;
  robot::OdometryAlphas alphas{0.05, 0.05, 0.05, 0.05};
  Vec<3> floor_std = Vec<3>(0.005, 0.005, 0.002);  ///< [m, m, rad] of the motion model
  robot::LaserMount mount;

  /// Throws InvalidArgument naming the first invalid option.
  void validate() const;
};

struct GridSlamParticle {
  robot::Pose pose = robot::Pose::Zero();
  TiledLogOddsGrid map;
  std::uint32_t node = 0;  ///< this pose's node in the trajectory tree
};

/// One pose of a particle's trajectory.
struct GridSlamPose {
  double time = 0.0;
  robot::Pose pose = robot::Pose::Zero();
};

struct GridSlamStep {
  bool processed = false;  ///< false: the gate skipped the scan
  double ess = 0.0;        ///< of the weights before resampling
  bool resampled = false;
  double log_likelihood_increment = 0.0;
  int failures = 0;             ///< particles whose proposal failed (weight zero)
  int fallbacks = 0;            ///< particles that sampled the motion model instead
  double mean_evaluations = 0;  ///< scan-likelihood evaluations per particle
  bool all_weights_zero = false;
};

class GridSlam {
 public:
  /// Throws InvalidArgument for invalid options or a null proposal.
  GridSlam(const GridSlamOptions& options, std::shared_ptr<const GridProposal> proposal);

  /// Every particle at x0 with the map of `scan` seen from there; `odometry` is the robot's
  /// odometry pose then. Throws InvalidArgument for a non-finite pose or an invalid scan.
  void initialize(const robot::Pose& x0, const robot::Pose& odometry, const robot::LaserScan& scan);
  /// One scan with the robot's odometry pose when it was taken (see the file comment). Throws
  /// InvalidArgument before any change for non-finite odometry or an invalid scan (named by its
  /// number among the scans accepted since initialize(), from 1), or when initialize() has not
  /// run.
  GridSlamStep step(const robot::Pose& odometry, const robot::LaserScan& scan);

  const GridSlamOptions& options() const { return options_; }
  const GridProposal& proposal() const { return *proposal_; }
  std::size_t steps() const { return steps_; }  ///< processed scans after the first
  std::span<const GridSlamParticle> particles() const { return engine_.particles(); }
  std::span<const double> weights() const { return engine_.weights(); }
  /// The particle of largest weight at the last step (before its resampling) and its map.
  std::size_t best_index() const { return best_; }
  const TiledLogOddsGrid& best_map() const { return engine_.particles()[best_].map; }
  /// The best particle's poses at the processed scans, first to last (times: the scans').
  std::vector<GridSlamPose> best_trajectory() const;
  /// Any particle's.
  std::vector<GridSlamPose> trajectory(std::size_t particle) const;

 private:
  struct Node {
    robot::Pose pose;
    double time;
    std::uint32_t parent;  ///< itself for the root
  };

  GridSlamOptions options_;
  std::shared_ptr<const GridProposal> proposal_;
  robot::OdometryModel motion_;
  filter::ParticleEngine<GridSlamParticle> engine_;
  std::vector<Node> nodes_;
  std::vector<GridProposalStats> stats_;
  std::vector<std::size_t> ancestors_;
  std::vector<double> uniforms_;
  ScanMatchBeams beams_;
  robot::Pose last_odometry_ = robot::Pose::Zero();
  bool initialized_ = false;
  std::size_t steps_ = 0;
  std::size_t calls_ = 0;
  std::size_t best_ = 0;
};

}  // namespace implicit::slam
