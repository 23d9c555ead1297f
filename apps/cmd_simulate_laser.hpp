#pragma once
// `implicit simulate --map`: a CARMEN laser log (or, --format robot-log, a robot log) of a
// differential-drive robot touring a map's free space, which `implicit mcl --sensor laser --map
// ... --data ...` reads back (docs/cli.md).

#include <string>
#include <vector>

#include "context.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace implicit::app {

struct LaserSimulationCommand {
  std::string map;            ///< --map: a map_server YAML file; empty: the landmark log
  std::string waypoints;      ///< --waypoints "x1,y1;x2,y2;..."; empty: the automatic tour
  double speed = 0.5;         ///< [m/s] while driving
  double turn_rate_deg = 45;  ///< [deg/s] while turning on the spot
  double scan_period = 0.2;   ///< [s] between scans
  double clearance = 0.3;     ///< [m] kept from every cell that is not free
  int laps = 1;
  int beams = 181;                      ///< over 180 degrees, as CARMEN's readers take FLASER lines
  double fov_deg = 180;                 ///< beams outside +-fov/2 read "no return"
  double range_max = 30;                ///< [m]
  std::string format = "carmen";        ///< --format: carmen or robot-log
  std::vector<double> odometry_alphas;  ///< robot-log: the odometry noise; empty: 0.02 each
};

/// [m] the laser's range noise sd when --range-sd is not given (its 0 means the landmark sensor's
/// default, and a noiseless laser here).
inline constexpr double kLaserRangeSd = 0.02;

/// Adds --map and the laser options (each needs --map) to the simulate subcommand; returns --map.
CLI::Option* add_laser_simulation_options(CLI::App& sub, LaserSimulationCommand& c);

/// Simulates and writes the log to ctx.out_dir (the FILE of --out); prints a summary line or,
/// with --json, the JSON object. `range_sd` is the laser's range noise sd [m].
void run_laser_simulation(const LaserSimulationCommand& c, double range_sd, const RunContext& ctx);

}  // namespace implicit::app
