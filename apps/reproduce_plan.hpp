#pragma once
// The plan of `implicit reproduce`: every configuration of every experiment (full or quick),
// with its settings and rough cost. Kept apart from running and reporting (cmd_reproduce.cpp).
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "context.hpp"

namespace implicit::app {

/// One configuration of one experiment: what to call, with which settings.
struct Config {
  std::string experiment;
  std::string label;  ///< human-readable, also the folder name of its CSV output
  nlohmann::json settings;
  double weight = 1.0;          ///< rough relative cost, for the overall ETA
  bool writes_figures = false;  ///< its CSV files go to DIR itself (the figure data)
  std::function<nlohmann::json(const RunContext&)> run;
};

struct Plan {
  std::vector<Config> configs;
  nlohmann::json settings;  ///< per experiment, the sweep as a whole (for the report)
};

/// The configurations to run: the paper's settings, or fewer runs with `quick`; only the
/// experiments named in `only` (all when empty).
Plan make_plan(bool quick, const std::vector<std::string>& only);

/// Adds the laser_mcl experiment (apps/reproduce_laser.cpp): laser MCL on the bundled ACES log.
void add_laser_mcl(Plan& plan, bool quick);

/// Adds the grid_slam experiment (apps/reproduce_grid_slam.cpp): grid SLAM on the bundled laser
/// logs with the three proposals.
void add_grid_slam(Plan& plan, bool quick);

/// Adds the da experiment (apps/reproduce_da.cpp): data assimilation on Lorenz-63 and Lorenz-96
/// beside DAPPER's published rmse.a.
void add_da(Plan& plan, bool quick);

}  // namespace implicit::app
