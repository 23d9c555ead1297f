// `implicit simulate`: a synthetic robot log (truth, surveyed landmarks, controls at irregular
// times, detections with landmark ids) for any shipped robot, read back by `mcl` and `slam`; with
// --map, a CARMEN laser log on an occupancy grid instead (cmd_simulate_laser.cpp).
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cmd_simulate_laser.hpp"
#include "context.hpp"
#include "experiments/motion_models.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/simulate.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct SimulateCommand {
  std::string model = "unicycle";
  RunContext ctx;  ///< --seed, and --out: here the log FILE
  robot::SimulationOptions options;
  experiments::MotionNoise noise;
  double range_sd = 0.0, bearing_sd_deg = 0.0;  ///< 0: the spec's Sigma2
  LaserSimulationCommand laser;
  CLI::Option* map = nullptr;  ///< --map: the laser mode
  CLI::Option* range_sd_option = nullptr;
};

template <typename Motion>
robot::RobotLog simulate(const SimulateCommand& c, const Motion& motion,
                         const robot::Driver& driver) {
  const robot::RangeBearingSensor sensor =
      c.range_sd > 0 || c.bearing_sd_deg > 0
          ? robot::RangeBearingSensor::from_std(c.range_sd > 0 ? c.range_sd : std::sqrt(0.05),
                                                c.bearing_sd_deg > 0
                                                    ? c.bearing_sd_deg * kPi / 180.0
                                                    : std::sqrt(0.05 * kPi / 180.0))
          : robot::RangeBearingSensor();
  return robot::simulate_robot_log(motion, sensor, driver, c.options, c.ctx.seed);
}

void setup_simulate(CLI::App& sub) {
  auto cmd = std::make_shared<SimulateCommand>();
  auto& c = *cmd;
  sub.add_option("--model", c.model, "The robot: " + experiments::motion_model_choices())
      ->check(CLI::IsMember(experiments::motion_model_names()))
      ->capture_default_str();
  add_common_options(sub, c.ctx);
  sub.get_option("--out")->description("The log FILE to write (gzip when it ends in .gz)");
  sub.get_option("--out")->required();
  sub.add_option("--steps", c.options.steps, "Motion steps")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--landmarks", c.options.landmarks, "Surveyed landmarks")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--scan-every", c.options.scan_every, "A scan at every k-th control")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--control-sd", c.noise.control_sd,
                 "Motion noise: sd of u1 and u2 (" + experiments::motion_noise_help() + ")")
      ->expected(2)
      ->check(in_range(0.0, 100.0));
  sub.add_option("--state-sd", c.noise.state_sd,
                 "Motion noise: sd of x [m], y [m], heading [rad] per sqrt(s); default: the "
                 "model's")
      ->expected(3)
      ->check(in_range(1e-9, 100.0));
  c.range_sd_option =
      sub.add_option("--range-sd", c.range_sd,
                     "Sensor range noise sd [m] (0: spec Sigma2, 0.224 m); with --map the "
                     "laser's (default 0.02, 0: noiseless)")
          ->check(in_range(0.0, 100.0));
  sub.add_option("--bearing-sd", c.bearing_sd_deg,
                 "Sensor bearing noise sd [deg] (0: spec Sigma2, 1.69 deg)")
      ->check(in_range(0.0, 90.0));
  c.map = add_laser_simulation_options(sub, c.laser);
  // The landmark robot's flags mean nothing to the laser log: refused, not ignored.
  for (const char* name : {"--model", "--steps", "--landmarks", "--scan-every", "--control-sd",
                           "--state-sd", "--bearing-sd"})
    sub.get_option(name)->excludes(c.map);
  set_examples(sub,
               {"implicit simulate --model unicycle --seed 3 --out u.log.gz",
                "implicit mcl --model unicycle --data u.log.gz --method implicit -M 100",
                "implicit simulate --map lab.yaml --seed 3 --out lab_sim.log",
                "implicit mcl --sensor laser --map lab.yaml --data lab_sim.log -M 100 --json"});
  sub.callback([cmd] {
    const SimulateCommand& c = *cmd;
    if (c.map->count() > 0) {
      run_laser_simulation(c.laser, c.range_sd_option->count() > 0 ? c.range_sd : kLaserRangeSd,
                           c.ctx);
      return;
    }
    // No declaration: the model's defaults, then the noise flags.
    const experiments::MotionModelEntry& entry =
        experiments::motion_model(c.model, "simulate --model");
    const robot::VehicleDeclaration declared = experiments::full_declaration(entry, {});
    const robot::AnyMotionModel model = experiments::make_motion_model(entry, declared, c.noise);
    const robot::Driver driver =
        entry.route_driver
            ? entry.route_driver(entry.route_speed, c.options.route_side)
            : robot::square_route_driver(entry.route_speed, c.options.route_side, true);
    robot::RobotLog log = experiments::visit_motion_model(
        model, [&](const auto& motion) { return simulate(c, motion, driver); });
    log.vehicle = declared;
    const std::string out = c.ctx.out_dir.string();
    try {
      robot::write_robot_log(out, log);
    } catch (const InvalidArgument& e) {  // the library names the file, not the flag
      throw InvalidArgument(fmt::format("--out: {}", e.what()));
    }
    std::size_t detections = 0;
    for (const auto& s : log.scans) detections += s.observations.size();
    nlohmann::json j{{"file", out},
                     {"model", c.model},
                     {"seed", c.ctx.seed},
                     {"steps", log.controls.size()},
                     {"seconds_simulated", log.controls.back().time},
                     {"landmarks", log.landmarks.size()},
                     {"scans", log.scans.size()},
                     {"detections", detections}};
    if (c.ctx.json) {
      fmt::print("{}\n", j.dump(2));
      return;
    }
    fmt::print("{}: {} model, {} steps over {:.1f} s, {} landmarks, {} scans with {} detections\n",
               out, c.model, log.controls.size(), log.controls.back().time, log.landmarks.size(),
               log.scans.size(), detections);
  });
}

const Registrar register_simulate{
    "simulate", "A synthetic robot log (any motion model the tool knows) for mcl and slam",
    setup_simulate};

}  // namespace
}  // namespace implicit::app
