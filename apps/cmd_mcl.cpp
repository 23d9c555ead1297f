// `implicit mcl`: Monte Carlo localization on the Car Park data (paper §4.1, Table 5, Figure 6).
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "cmd_mcl_laser.hpp"
#include "context.hpp"
#include "experiments.hpp"
#include "experiments/choices.hpp"
#include "experiments/motion_models.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/robot/bag.hpp"
#include "nav2_params.hpp"
#include "plural.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct MclCommand {
  MclSettings settings;
  RunContext ctx;
  bool allow_empty = false;
  CLI::Option* particles = nullptr;  ///< -M, to tell a given count from the default
  LaserCommand laser;
  std::string map;  ///< --map: linear|random (landmark), or a map file (laser)
  /// The choices of the landmark runs as given, parsed by experiments/choices.hpp.
  std::string config = "A", implicit_map = "linear", sigma2 = "variance", truth = "gps";
};

/// The options of global localization, kidnapping, recovery and KLD-sampling (spec §3.11).
void add_global_options(CLI::App& sub, MclSettings& s) {
  sub.add_option("--init", s.init,
                 "known: start from the log's initial pose; global: no initial pose (run r starts "
                 "r * span / runs seconds in, at its first scan with >= 2 detections)")
      ->check(CLI::IsMember({"known", "global"}))
      ->capture_default_str();
  sub.add_option("--start-span", s.start_span, "[s] The global starts' spread over the log")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--duration", s.duration,
                 "[s] Global and kidnapping runs use the log up to this long after the first "
                 "control (all runs end together); 0: to the end of the log")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--kidnap-at", s.kidnap_at,
                 "[s] after the first control: drop --kidnap-skip seconds of odometry and scans "
                 "there, so the filter's pose is wrong without being told")
      ->check(in_range(0.0, 1e6));
  sub.add_option("--kidnap-skip", s.kidnap_skip, "[s] Length of the dropped stretch")
      ->check(in_range(1e-6, 1e6))
      ->capture_default_str();
  sub.add_option("--recovery", s.recovery,
                 "Injection when the filter looks lost: none, uniform (AMCL's source), mixture "
                 "(over the minima of -log p(z|x)); auto: off for a known start, else uniform for "
                 "standard and mixture for implicit (also the global start's source)")
      ->check(CLI::IsMember({"auto", "none", "uniform", "mixture"}))
      ->capture_default_str();
  sub.add_option("--recovery-alpha-slow", s.recovery_alpha_slow, "Rate of the slow average")
      ->check(in_range(1e-9, 1.0))
      ->capture_default_str();
  sub.add_option("--recovery-alpha-fast", s.recovery_alpha_fast, "Rate of the fast average")
      ->check(in_range(1e-9, 1.0))
      ->capture_default_str();
  sub.add_option("--kidnap-probability", s.kidnap_probability,
                 "Prior probability per update that the robot was moved unseen (weights of the "
                 "injected particles)")
      ->check(in_range(1e-300, 0.5))
      ->capture_default_str();
  sub.add_flag("--kld", s.kld, "Adaptive particle count by KLD-sampling (resamples every update)");
  sub.add_option("--kld-err", s.kld_err, "KLD-sampling: bound on the K-L divergence")
      ->check(in_range(1e-6, 1.0))
      ->capture_default_str();
  sub.add_option("--kld-z", s.kld_z, "KLD-sampling: upper standard normal quantile")
      ->check(in_range(0.0, 10.0))
      ->capture_default_str();
  sub.add_option("--min-particles", s.min_particles, "KLD-sampling: fewest particles")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--max-particles", s.max_particles,
                 "KLD-sampling: most particles (and a global start's count)")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--cover-spacing", s.cover_spacing,
                 "[m] Grid of the multi-start Newton over the map (mixture source)")
      ->check(in_range(0.05, 100.0))
      ->capture_default_str();
  sub.add_option("--cover-headings", s.cover_headings, "Headings per grid point (mixture source)")
      ->check(in_range(1, 360))
      ->capture_default_str();
}

/// The landmark or laser runs of `implicit mcl` once the flags are parsed, and their printout.
void run_mcl_command(MclCommand& cmd, CLI::App& sub, const CLI::Option* sensor) {
  ThreadLimit limit(cmd.ctx.threads);
  if (!cmd.laser.params.empty()) {
    // nav2's AMCL localizes with a laser: its parameters imply --sensor laser.
    if (sensor->count() == 0) cmd.laser.sensor = "laser";
    require(cmd.laser.sensor == "laser",
            "mcl --params: nav2's AMCL parameters apply to --sensor laser, got --sensor {}",
            cmd.laser.sensor);
    cmd.laser.params_record =
        apply_nav2_params(sub, cmd.laser.params, robot::is_bag(cmd.settings.data_dir));
  }
  // --implicit-map is the implicit proposal's map for both sensors (for landmarks --map too).
  cmd.settings.map = experiments::parse_implicit_map(cmd.implicit_map);
  if (cmd.laser.sensor == "laser") {
    run_laser_mcl_command(cmd.settings, cmd.map, cmd.laser, cmd.ctx, cmd.allow_empty);
    return;
  }
  if (!cmd.map.empty()) {
    require(cmd.map == "linear" || cmd.map == "random",
            "mcl: --map takes a map file only with --sensor laser; for landmarks it is "
            "the implicit proposal's map, linear or random, got '{}'",
            cmd.map);
    cmd.implicit_map = cmd.map;
  }
  cmd.settings.config = experiments::parse_noise_config(cmd.config);
  cmd.settings.map = experiments::parse_implicit_map(cmd.implicit_map);
  cmd.settings.sigma2 = experiments::parse_sigma2(cmd.sigma2);
  cmd.settings.truth = experiments::parse_mcl_truth(cmd.truth);
  cmd.settings.allow_empty = cmd.allow_empty;
  cmd.settings.trajectory = cmd.laser.trajectory;
  cmd.settings.truth_trajectory = cmd.laser.truth_trajectory;
  // M = 100 is the tracking default; started without a pose it finds the car in too few runs,
  // so a global start without -M adapts its count by KLD-sampling (spec §3.11).
  if (cmd.settings.init == "global" && cmd.particles->count() == 0) cmd.settings.kld = true;
  const auto r = run_mcl(cmd.settings, cmd.ctx);
  const auto check = [&] {
    require_scored(r, "mcl", {"error_percent_mean", "rmse_m"}, {}, cmd.allow_empty);
  };
  if (cmd.ctx.json) {
    print_json(r);
    if (!r.contains("global_success_rate") && !r.contains("kidnap_recovery_rate")) check();
    return;
  }
  if (r.contains("global_success_rate") || r.contains("kidnap_recovery_rate")) {
    const bool kidnap = r.contains("kidnap_recovery_rate");
    const double rate = r[kidnap ? "kidnap_recovery_rate" : "global_success_rate"].get<double>();
    fmt::print(
        "MCL {} {} M = {}, {}: {} rate {}, median time {:.1f} s, particles {:.0f} "
        "(peak {:.0f}), {:.4f} ms per step\n",
        kidnap ? "kidnapping" : "global start", r["method"].get<std::string>(),
        r["particles"].get<int>(), counted(r["runs"].get<int>(), "run", "runs"),
        kidnap ? "recovery" : "success",
        std::isfinite(rate) ? fmt::format("{:.2f}", rate) : "n/a (nothing was tested)",
        r[kidnap ? "recovery_time_s_median" : "time_to_converge_s_median"].get<double>(),
        r["particles_mean"].get<double>(), r["particles_peak"].get<double>(),
        r["cpu_ms_per_step"].get<double>());
    return;
  }
  // Configs A and B are the Car Park's two noise settings of the Ute; another log says which
  // log and model it ran with (a model without the Car Park's noise has no config).
  const std::string& data = cmd.settings.data_dir;
  const std::string model = r["model"].get<std::string>();
  const std::string setting =
      data.empty() || std::filesystem::is_directory(data)
          ? fmt::format("config {}", r["config"].get<std::string>())
          : fmt::format("log {}, {} model{}", data, model,
                        experiments::motion_model(model, "mcl --model").car_park_noise
                            ? ", config " + r["config"].get<std::string>()
                            : "");
  fmt::print(
      "MCL {} M = {}, {}, {}:\n"
      "  err% = {:.2f} ± {:.2f} (median {:.2f}), RMSE {:.3f} m, heading RMSE {:.4f} rad\n"
      "  lost runs {}, ESS/M {:.2f}, {:.4f} ms per step, {:.1f} s\n",
      r["method"].get<std::string>(), r["particles"].get<int>(), setting,
      counted(r["runs"].get<int>(), "run", "runs"), r["error_percent_mean"].get<double>(),
      r["error_percent_std"].get<double>(), r["error_percent_median"].get<double>(),
      r["rmse_m"].get<double>(), r["heading_rmse_rad"].get<double>(), r["lost_runs"].get<int>(),
      r["ess_mean"].get<double>(), r["cpu_ms_per_step"].get<double>(), r["seconds"].get<double>());
  check();
}

void setup_mcl(CLI::App& sub) {
  auto cmd = std::make_shared<MclCommand>();
  sub.add_option("--method", cmd->settings.method, experiments::mcl_methods().help())
      ->check(CLI::IsMember(experiments::mcl_methods().names()))
      ->capture_default_str();
  cmd->particles =
      sub.add_option("--particles,-M", cmd->settings.particles,
                     "Particles M (landmarks, --init global without -M: KLD-sampling between "
                     "--min-particles and --max-particles instead, AMCL's way)")
          ->check(in_range(1, 10000000))
          ->capture_default_str();
  sub.add_option("--runs", cmd->settings.runs, "Runs with different seeds")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--data", cmd->settings.data_dir,
                 "A Car Park folder (carpark_*.csv) or a plain-text robot log (docs/formats.md); "
                 "default: the bundled data/carpark");
  sub.add_option("--config", cmd->config,
                 "Noise setting: A = the paper's P = 0.5, B = P = 0.1 (spec §3.9)")
      ->check(CLI::IsMember({"A", "B"}))
      ->capture_default_str();
  sub.add_option("--p", cmd->settings.p,
                 "Control noise P (std of speed [m/s] and steering [rad]); overrides --config")
      ->check(in_range(0.0, 10.0));
  sub.add_option("--q", cmd->settings.q, "State noise q1 = q2 [m] (default 0.1)")
      ->check(in_range(1e-6, 10.0));
  sub.add_option("--implicit-map", cmd->implicit_map, "Implicit proposal map: linear or random")
      ->check(CLI::IsMember({"linear", "random"}))
      ->capture_default_str();
  sub.add_option("--map", cmd->map,
                 "laser: the occupancy grid, a map_server YAML file (default: built from the log's "
                 "reference poses); landmark: linear or random, as --implicit-map");
  sub.add_option("--sigma2", cmd->sigma2,
                 "Reading of Table 7's Sigma2 entries: variance (spec E27) or std")
      ->check(CLI::IsMember({"variance", "std"}))
      ->capture_default_str();
  sub.add_option(
         "--truth", cmd->truth,
         "Ground truth: gps (fixes interpolated in time) or reference (a GPS-aided implicit "
         "MCL run with many particles, cached; docs/cli.md)")
      ->check(CLI::IsMember({"gps", "reference"}))
      ->capture_default_str();
  sub.add_option("--gps-std", cmd->settings.gps_std,
                 "GPS std [m] per coordinate assumed by the reference run")
      ->check(in_range(1e-3, 100.0))
      ->capture_default_str();
  sub.add_option("--reference-particles", cmd->settings.reference_particles,
                 "Particles of the reference run")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--model", cmd->settings.model,
                 "The robot: " + experiments::motion_model_choices() +
                     "; default: the vehicle the log declares (ute when it declares none). A log "
                     "declaring another vehicle is refused (exit 1)")
      ->check(CLI::IsMember(experiments::motion_model_names()));
  sub.add_option("--control-sd", cmd->settings.control_sd,
                 "Motion noise: sd of u1 u2 (" + experiments::motion_noise_help() +
                     "; for the ute it overrides --p)")
      ->expected(2)
      ->check(in_range(0.0, 100.0));
  sub.add_option("--state-sd", cmd->settings.state_sd,
                 "Motion noise: sd of x [m], y [m], heading [rad] per sqrt(s), overrides --q")
      ->expected(3)
      ->check(in_range(1e-9, 100.0));
  sub.add_option("--range-sd", cmd->settings.range_sd,
                 "Sensor range noise sd [m] (0: Table 7's Sigma2 read per --sigma2)")
      ->check(in_range(0.0, 100.0));
  sub.add_option("--bearing-sd", cmd->settings.bearing_sd_deg,
                 "Sensor bearing noise sd [deg] (0: Table 7's Sigma2 read per --sigma2)")
      ->check(in_range(0.0, 90.0));
  sub.add_flag("--no-clutter{false}", cmd->settings.clutter,
               "Dropped detections contribute nothing (instead of the clutter density p0)");
  sub.add_option("--label-gate", cmd->settings.label_gate,
                 "Labelled detections whose d^2 against the predicted pose exceeds this are left "
                 "out of the step and counted (labelled_gated); 0 trusts every label (default: "
                 "the 2-dof chi-square quantile at 1 - 1e-6)")
      ->check(in_range(0.0, 1e6));
  add_global_options(sub, cmd->settings);
  add_laser_options(sub, cmd->laser);
  sub.add_flag("--allow-empty", cmd->allow_empty,
               "Exit 0 even when the run scored nothing (no step with truth, no landmark, a "
               "non-finite metric); a warning is printed either way");
  add_common_options(sub, cmd->ctx);
  set_examples(sub, {"implicit mcl --method implicit --particles 100 --runs 20 --json",
                     "implicit mcl --model unicycle --data u.log.gz --method implicit -M 100",
                     "implicit mcl --method standard --particles 300 --config B --out out/mcl",
                     "implicit mcl --init global --method implicit -M 200 --runs 20 --json",
                     "implicit mcl --kidnap-at 60 --kidnap-skip 10 --method standard --kld",
                     "implicit mcl --sensor laser --data data/carmen/intel-corrected.log.gz "
                     "--method implicit -M 100 --runs 10 --json"});
  const CLI::Option* sensor = sub.get_option("--sensor");
  sub.callback([cmd, &sub, sensor] { run_mcl_command(*cmd, sub, sensor); });
}

const Registrar register_mcl{"mcl", "Monte Carlo localization on the Car Park data (paper Table 5)",
                             setup_mcl};

}  // namespace
}  // namespace implicit::app
