// `implicit slam`: EKF-SLAM, FastSLAM 1.0/2.0 and implicit SLAM (paper §4.2, Table 6, Figure 7).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "cmd_slam_laser.hpp"
#include "context.hpp"
#include "experiments.hpp"
#include "experiments/choices.hpp"
#include "experiments/motion_models.hpp"
#include "implicit/core/parallel.hpp"
#include "plural.hpp"
#include "registry.hpp"
#include "tum_output.hpp"

namespace implicit::app {
namespace {

/// A metric of the JSON for the text summary: null (not computable, e.g. the map metrics of a
/// data set without a true map, the errors of a log without truth) reads "n/a" rather than a
/// number that looks like a result.
std::string metric_text(const nlohmann::json& value, int digits, const char* unit = "") {
  // In memory a metric that could not be computed is a NaN number; only dump() makes it null.
  if (!value.is_number() || !std::isfinite(value.get<double>())) return "n/a";
  return fmt::format("{:.{}f}{}", value.get<double>(), digits, unit);
}

struct SlamCommand {
  SlamSettings settings;
  std::string truth = "paper";  ///< --truth as given, parsed by experiments/choices.hpp
  RunContext ctx;
  bool allow_empty = false;
  GridSlamCommand grid;
};

/// The landmark or laser runs of `implicit slam` once the flags are parsed, and their printout.
void run_slam_command(SlamCommand& cmd) {
  ThreadLimit limit(cmd.ctx.threads);
  if (cmd.grid.sensor == "laser") {
    run_grid_slam_command(cmd.settings, cmd.grid, cmd.ctx);
    return;
  }
  if (cmd.settings.method == "bootstrap" || cmd.settings.method == "gmapping")
    throw CLI::ValidationError(
        "--method",
        fmt::format("{} is a grid-SLAM proposal; it needs --sensor laser", cmd.settings.method));
  for (const CLI::Option* o : cmd.grid.laser_only)
    if (o->count() > 0)
      throw CLI::ValidationError(o->get_name(), "applies to grid SLAM (--sensor laser)");
  cmd.settings.truth = experiments::parse_slam_truth(cmd.truth);
  cmd.settings.g2o = cmd.grid.g2o;  // declared with the laser flags, written by both paths
  const auto r = run_slam(cmd.settings, cmd.ctx);
  const auto check = [&] {
    require_scored(r, "slam", {"error_percent_mean", "rmse_pose_m"},
                   {"steps_per_dataset", "scored_steps_min", "landmarks_mean"}, cmd.allow_empty);
  };
  if (cmd.ctx.json) {
    print_json(r);
    check();
    return;
  }
  fmt::print(
      "SLAM {}, M = {}, {} ({} association):\n"
      "  err% = {} ± {} (aligned {}), pose RMSE {}\n"
      "  map RMSE {}, map shape {}, {:.1f} landmarks\n"
      "  {:.3f} ms CPU per step, peak memory {:.1f} MB, {:.1f} s\n",
      r["method"].get<std::string>(), r["particles"].get<int>(),
      counted(r["datasets"].get<int>(), "data set", "data sets"),
      r["association"].get<std::string>(), metric_text(r["error_percent_mean"], 2),
      metric_text(r["error_percent_std"], 2), metric_text(r["error_aligned_percent_mean"], 2),
      metric_text(r["rmse_pose_m"], 3, " m"), metric_text(r["rmse_map_m"], 3, " m"),
      metric_text(r["map_shape_m"], 3, " m"), r["landmarks_mean"].get<double>(),
      r["cpu_ms_per_step"].get<double>(), r["peak_memory_mb"].get<double>(),
      r["seconds"].get<double>());
  check();
}

void setup_slam(CLI::App& sub) {
  auto cmd = std::make_shared<SlamCommand>();
  auto& s = cmd->settings;
  std::vector<std::string> methods = experiments::landmark_slam_methods().names();
  for (const std::string& m : experiments::grid_slam_methods().names())
    if (std::find(methods.begin(), methods.end(), m) == methods.end()) methods.push_back(m);
  sub.add_option("--method", s.method,
                 experiments::landmark_slam_methods().help() +
                     "; --sensor laser: " + experiments::grid_slam_methods().help())
      ->check(CLI::IsMember(methods))
      ->capture_default_str();
  cmd->grid.particles = sub.add_option("--particles,-M", s.particles,
                                       "Particles M (ignored by ekf; --sensor laser: default 30)")
                            ->check(in_range(1, 1000000))
                            ->capture_default_str();
  cmd->grid.datasets =
      sub.add_option(
             "--datasets", s.datasets,
             "Data sets (synthetic seeds seed, seed+1, ...; with --data: repeated runs; --sensor "
             "laser: runs, default 1)")
          ->check(in_range(1, 100000))
          ->capture_default_str();
  sub.add_option("--data", s.data_dir,
                 "Plain-text robot log (or a folder of *.log[.gz]) instead of synthetic data, e.g. "
                 "data/victoria_park/victoria_park.log.gz");
  sub.add_option("--association", s.association,
                 "known: true landmark ids; ml: maximum likelihood with a chi-square gate")
      ->check(CLI::IsMember({"ml", "known"}))
      ->capture_default_str();
  sub.add_option("--truth", cmd->truth,
                 "paper: noise-free truth (Table 6); consistent: truth sampled from the model "
                 "(NEES)")
      ->check(CLI::IsMember({"paper", "consistent"}))
      ->capture_default_str();
  sub.add_option("--laser-every", s.laser_every, "Synthetic laser every k-th motion step")
      ->check(in_range(1, 10000))
      ->capture_default_str();
  sub.add_option("--noise-scale", s.consistent_noise_scale,
                 "Sigma1 factor of the consistent truth and the filters")
      ->check(in_range(1e-6, 1.0))
      ->capture_default_str();
  sub.add_option("--control-noise", s.control_noise, "P = diag(p, p) of the motion model")
      ->check(in_range(1e-6, 10.0))
      ->capture_default_str();
  sub.add_option("--dense-landmarks", s.dense_landmarks,
                 "Synthetic dense landmark field with this many landmarks (0 = the 15 beacons)")
      ->check(in_range(0, 1000000))
      ->capture_default_str();
  sub.add_option("--dense-laps", s.dense_laps, "Route length of the dense field (laps)")
      ->check(in_range(1, 1000))
      ->capture_default_str();
  sub.add_option("--min-range", s.min_range, "Ignore detections closer than this [m]")
      ->check(in_range(0.0, 100.0))
      ->capture_default_str();
  sub.add_option("--range-sd", s.range_sd,
                 "Filters' range noise sd [m] (0 = spec Sigma2: 0.224 m; synthetic data keep it)")
      ->check(in_range(0.0, 100.0));
  sub.add_option("--bearing-sd", s.bearing_sd_deg,
                 "Filters' bearing noise sd [deg] (0 = spec Sigma2: 1.69 deg)")
      ->check(in_range(0.0, 90.0));
  sub.add_option("--gate-chi2", s.gate_chi2,
                 "ML association gate on the squared Mahalanobis distance (0 = 9.21, chi2_2 99 %)")
      ->check(in_range(0.0, 1e6));
  sub.add_option("--new-landmark-density", s.new_landmark_density,
                 "p0, likelihood of a new landmark [1/(m rad)] (0 = 1/(15 pi))")
      ->check(in_range(0.0, 1e6));
  sub.add_flag("--allow-empty", cmd->allow_empty,
               "Exit 0 even when the run scored nothing (no step with truth, no landmark, a "
               "non-finite metric); a warning is printed either way");
  sub.add_option("--model", s.model,
                 "The robot: " + experiments::motion_model_choices() +
                     "; default: the vehicle the log declares (ute when it declares none). A log "
                     "declaring another vehicle is refused (exit 1)")
      ->check(CLI::IsMember(experiments::motion_model_names()));
  sub.add_option("--control-sd", s.control_sd,
                 "Motion noise: sd of u1 u2 (" + experiments::motion_noise_help() +
                     "; for the ute it overrides --control-noise)")
      ->expected(2)
      ->check(in_range(0.0, 100.0));
  sub.add_option("--state-sd", s.state_sd,
                 "Motion noise: sd of x [m], y [m], heading [rad] per sqrt(s)")
      ->expected(3)
      ->check(in_range(1e-9, 100.0));
  sub.add_option("--trajectory", s.trajectory,
                 "Write the first run's path as a TUM trajectory file (t x y z qx qy qz qw; t in "
                 "seconds from the first pose), for implicit eval")
      ->check(tum_file_validator());
  sub.add_option("--truth-trajectory", s.truth_trajectory,
                 "Write the first data set's truth (its steps with a known pose) as a TUM file")
      ->check(tum_file_validator());
  add_grid_slam_options(sub, cmd->grid);
  // --g2o is declared with the laser flags but the landmark path writes one too.
  CLI::Option* g2o = sub.get_option("--g2o");
  std::erase(cmd->grid.laser_only, g2o);
  g2o->description(
      "Write the first run's pose graph as a g2o file, for post-optimisation: its trajectory as "
      "VERTEX_SE2 and the odometry between consecutive poses as EDGE_SE2 with the information of "
      "the filter's motion noise; landmark SLAM adds its map as VERTEX_XY and each detection as "
      "EDGE_SE2_XY (docs/formats.md)");
  for (const char* name :
       {"--association", "--truth", "--laser-every", "--noise-scale", "--control-noise",
        "--dense-landmarks", "--dense-laps", "--min-range", "--range-sd", "--bearing-sd",
        "--gate-chi2", "--new-landmark-density", "--model", "--control-sd", "--state-sd"})
    cmd->grid.landmark_only.push_back(sub.get_option(name));
  add_common_options(sub, cmd->ctx);
  set_examples(sub, {"implicit slam --method implicit-rb --particles 100 --datasets 10 --json",
                     "implicit slam --method ekf --datasets 50 --out out/slam",
                     "implicit slam --model unicycle --data u.log.gz --method implicit-rb -M 100",
                     "implicit slam --method fastslam2 --association ml --data "
                     "data/victoria_park/victoria_park.log.gz --datasets 1 --json",
                     "implicit slam --sensor laser --data data/carmen/intel-corrected.log.gz "
                     "--method implicit -M 8 --datasets 3 --map-out out/intel.yaml --json"});
  sub.callback([cmd] { run_slam_command(*cmd); });
}

const Registrar register_slam{
    "slam", "Landmark SLAM: EKF, FastSLAM 1.0/2.0, implicit (paper Table 6)", setup_slam};

}  // namespace
}  // namespace implicit::app
