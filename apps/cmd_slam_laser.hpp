#pragma once
// `implicit slam --sensor laser`: grid SLAM on a CARMEN laser log by the semi-synthetic protocol,
// or on a ROS bag with its recorded odometry (slam/grid/grid_slam_run.hpp does the work;
// docs/cli.md, "Grid SLAM").

#include <string>
#include <vector>

#include "bag_flags.hpp"
#include "context.hpp"
#include "experiments.hpp"
#include "experiments/grid_slam.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace implicit::app {

struct GridSlamCommand {
  std::string sensor = "landmark";  ///< landmark | laser
  std::vector<double> alphas;       ///< the odometry noise (empty: the runner's)
  int max_scans = 0;                ///< 0: every scan
  int map_min_echoes = -1;          ///< -1: GridSlamOptions' default
  std::string map_out;              ///< the first run's map as map_server YAML + PGM
  std::string g2o;                  ///< the first run's pose graph as a g2o file
  BagFlags bag;                     ///< topics and frames when --data is a ROS bag
  /// The grid-SLAM options, refused with --sensor landmark (add_grid_slam_options fills it).
  std::vector<CLI::Option*> laser_only;
  /// The landmark options, refused with --sensor laser (they would be silently ignored).
  std::vector<CLI::Option*> landmark_only;
  CLI::Option *particles = nullptr, *datasets = nullptr;
};

/// Advances `bar` (of runs x 1000 units) in thousandths of each run: the scans a run processes
/// are known only once it has started. The bar must outlive the returned function.
experiments::GridSlamProgress grid_slam_progress(Progress& bar);

/// Adds --sensor and the grid-SLAM options to the slam subcommand.
void add_grid_slam_options(CLI::App& sub, GridSlamCommand& g);

/// Runs grid SLAM with the slam subcommand's shared settings (method, particles, data sets as
/// seeds, data, trajectory files) and prints JSON or a summary.
void run_grid_slam_command(const SlamSettings& shared, const GridSlamCommand& g,
                           const RunContext& ctx);

}  // namespace implicit::app
