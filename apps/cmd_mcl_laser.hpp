#pragma once
// `implicit mcl --sensor laser`: the laser options of the mcl subcommand and their run
// (experiments/laser_mcl.hpp does the work).

#include <optional>
#include <string>
#include <vector>

#include "bag_flags.hpp"
#include "context.hpp"
#include "experiments.hpp"
#include "experiments/laser_mcl.hpp"
#include "nav2_params.hpp"

namespace CLI {
class App;
}

namespace implicit::app {

struct LaserCommand {
  std::string sensor = "landmark";  ///< landmark | laser
  experiments::LaserMclSettings settings;
  std::vector<double> alphas, filter_alphas;
  std::string interpolation = "bicubic", aggregation = "product";
  std::string laser_model = "likelihood-field";
  std::string estimate = "mean";  ///< --estimate: mean | cluster
  BagFlags bag;                   ///< a ROS bag as --data: its topics and frames
  std::string trajectory;         ///< TUM file of the first run's estimate
  std::string truth_trajectory;   ///< TUM file of the reference (--truth-trajectory)
  std::string params;             ///< --params: a nav2 parameter file (its amcl block)
  std::optional<Nav2ParamsRecord> params_record;  ///< what --params set, for the JSON
};

/// Adds --sensor and the laser's options to the mcl subcommand.
void add_laser_options(CLI::App& sub, LaserCommand& laser);

/// Runs laser MCL with the mcl subcommand's shared settings (method, particles, runs, data,
/// map file, init, seed) and the laser options; prints JSON or a summary.
void run_laser_mcl_command(const MclSettings& shared, const std::string& map_file,
                           LaserCommand& laser, const RunContext& ctx, bool allow_empty);

}  // namespace implicit::app
