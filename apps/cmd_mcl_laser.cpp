// `implicit mcl --sensor laser`: laser scans on an occupancy grid, by the semi-synthetic protocol
// on a CARMEN log, or on a robot log's recorded odometry (docs/cli.md, "Laser localization").
#include "cmd_mcl_laser.hpp"

#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "experiments/choices.hpp"
#include "implicit/core/error.hpp"
#include "tum_output.hpp"

namespace implicit::app {

void add_laser_options(CLI::App& sub, LaserCommand& l) {
  auto& s = l.settings;
  add_bag_flags(sub, l.bag);
  sub.add_option("--sensor", l.sensor, experiments::sensors().help())
      ->check(CLI::IsMember(experiments::sensors().names()))
      ->capture_default_str();
  sub.add_option("--laser-model", l.laser_model, "laser: " + experiments::laser_models().help())
      ->check(CLI::IsMember(experiments::laser_models().names()))
      ->capture_default_str();
  sub.add_option("--z-short", s.beam.z_short, "laser, beam model: weight of an unexpected obstacle")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--z-max", s.beam.z_max, "laser, beam model: weight of a missed echo (no return)")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--lambda-short", s.beam.lambda_short,
                 "laser, beam model: [1/m] rate of the unexpected obstacles' exponential")
      ->check(in_range(1e-6, 1e6))
      ->capture_default_str();
  sub.add_option("--alphas", l.alphas,
                 "laser: alpha1..alpha4 of the odometry synthesised from a CARMEN log's "
                 "reference poses (nav2's names; default 0.02 each; a robot log's odometry is "
                 "recorded)")
      ->expected(4)
      ->check(in_range(0.0, 10.0));
  sub.add_option("--filter-alphas", l.filter_alphas,
                 "laser: alpha1..alpha4 of the filter's odometry model (default: --alphas)")
      ->expected(4)
      ->check(in_range(0.0, 10.0));
  sub.add_option("--z-hit", s.laser.z_hit, "laser: weight of the hit component")
      ->check(in_range(1e-9, 1e6))
      ->capture_default_str();
  sub.add_option("--z-rand", s.laser.z_rand, "laser: weight of the uniform component")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--sigma-hit", s.laser.sigma_hit, "laser: [m] std of a hit")
      ->check(in_range(1e-4, 100.0))
      ->capture_default_str();
  sub.add_option("--max-beams", s.laser.max_beams, "laser: beams used per scan")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--laser-max-dist", s.laser.laser_likelihood_max_dist,
                 "laser: [m] distances to the nearest obstacle are capped here "
                 "(nav2's laser_likelihood_max_dist)")
      ->check(in_range(1e-3, 100.0))
      ->capture_default_str();
  sub.add_option("--laser-max-range", s.laser.laser_max_range,
                 "laser: [m] readings at or beyond are no return; <= 0: the log's")
      ->check(in_range(-1.0, 1e4));
  sub.add_option("--interpolation", l.interpolation,
                 "laser: distance field between cell centres: nearest (AMCL's lookup; bootstrap "
                 "only), bilinear, bicubic (C1; the implicit proposal's default)")
      ->check(CLI::IsMember({"nearest", "bilinear", "bicubic"}))
      ->capture_default_str();
  sub.add_option("--aggregation", l.aggregation,
                 "laser: product (the likelihood) or cubed-sum (nav2's 1 + sum p^3; bootstrap "
                 "only, for parity)")
      ->check(CLI::IsMember({"product", "cubed-sum"}))
      ->capture_default_str();
  sub.add_option("--update-min-d", s.data.update_min_d,
                 "laser: [m] update after this much travel (nav2's update_min_d)")
      ->check(in_range(0.0, 100.0))
      ->capture_default_str();
  sub.add_option("--update-min-a", s.data.update_min_a,
                 "laser: [rad] or after this much turning (nav2's update_min_a)")
      ->check(in_range(0.0, 10.0))
      ->capture_default_str();
  sub.add_option("--map-resolution", s.data.map_resolution,
                 "laser: [m] cell size of the map built from the reference poses (no map file)")
      ->check(in_range(0.005, 1.0))
      ->capture_default_str();
  sub.add_option("--map-min-echoes", s.data.map_min_echoes,
                 "laser: a cell of the built map where beams of this many scans ended is occupied, "
                 "whatever the beams that crossed it (0: log-odds only)")
      ->check(in_range(0, 255))
      ->capture_default_str();
  sub.add_option("--max-updates", s.data.max_updates, "laser: use the first N updates (0: all)")
      ->check(in_range(0, 100000000));
  sub.add_option("--estimate", l.estimate,
                 "laser: the pose reported at each update: mean (of all particles) or cluster "
                 "(the weighted mean of the heaviest cluster, as AMCL reports; stays on one place "
                 "while the posterior has several)")
      ->check(CLI::IsMember({"mean", "cluster"}))
      ->capture_default_str();
  sub.add_option("--global-updates", s.global_updates,
                 "laser, --init global: a start succeeds if the error is below "
                 "--global-radius from this update on")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--global-radius", s.global_success_radius,
                 "laser, --init global: [m] success radius")
      ->check(in_range(1e-3, 100.0))
      ->capture_default_str();
  sub.add_option("--starts", s.implicit_starts,
                 "laser, implicit: Newton starts per particle (the prediction, and draws from the "
                 "motion prior); the lowest minimum centres the proposal (weights stay exact)")
      ->check(in_range(1, 64))
      ->capture_default_str();
  sub.add_option("--start-probe", s.implicit_start_probe,
                 "laser, implicit: Newton iterations a further start runs before it must be below "
                 "the best minimum found, else it is dropped (0: every start runs to convergence; "
                 "weights stay exact either way)")
      ->check(in_range(0, 20))
      ->capture_default_str();
  sub.add_option("--defensive", s.implicit_defensive,
                 "laser, implicit (linear map): share of samples drawn from the motion prior "
                 "instead, weighted by the mixture's density (a particle survives when every "
                 "Newton start found the wrong minimum)")
      ->check(in_range(0.0, 0.99))
      ->capture_default_str();
  sub.add_option("--trajectory", l.trajectory,
                 "Write the first run's estimate as a TUM trajectory file (t x y z qx qy qz qw), "
                 "for implicit eval")
      ->check(tum_file_validator());
  sub.add_option("--params", l.params,
                 "A nav2 parameter file: its amcl block's keys set the laser flags of the same "
                 "meaning (flags given here win; keys without a meaning here are named on "
                 "stderr); implies --sensor laser")
      ->check(CLI::ExistingFile);
  sub.add_option("--truth-trajectory", l.truth_trajectory,
                 "Write the reference the runs are scored against as a TUM file (its steps with a "
                 "known pose)")
      ->check(tum_file_validator());
}

namespace {

robot::OdometryAlphas alphas_of(const std::vector<double>& v, const robot::OdometryAlphas& d) {
  if (v.empty()) return d;
  return {v[0], v[1], v[2], v[3]};
}

/// --recovery for a laser run: uniform (AMCL's source over free space) or none; auto is none.
/// A global start does not need it (its first particles cover the map), and it hurts there:
/// on Intel, implicit M = 1000, 20 global starts succeeded 18 times without injection and 16
/// times with it (docs/performance.md). The landmark runs' mixture source is not one the laser
/// has.
bool laser_recovery(const MclSettings& shared) {
  require(shared.recovery != "mixture",
          "mcl --sensor laser: --recovery mixture is the landmark runs' source; a laser run "
          "takes --recovery uniform, none or auto");
  require(shared.kidnap_at < 0,
          "mcl --sensor laser: --kidnap-at is not available for laser runs; kidnapping is "
          "tested on the landmark logs");
  return shared.recovery == "uniform";
}

void write_tum_files(const LaserCommand& l, const experiments::LaserMclResult& r,
                     const experiments::LaserDataset& d) {
  if (!l.trajectory.empty()) {
    TumTrack est;
    const auto& poses = r.runs.front().estimates;
    for (std::size_t k = 0; k < poses.size(); ++k) est.add(d.scans[k].time, poses[k]);
    est.write(l.trajectory, "mcl --trajectory");
  }
  if (!l.truth_trajectory.empty()) {
    TumTrack truth;
    for (std::size_t k = 0; k < d.reference.size(); ++k) truth.add(d.scans[k].time, d.reference[k]);
    truth.write(l.truth_trajectory, "mcl --truth-trajectory");
  }
}

}  // namespace

void run_laser_mcl_command(const MclSettings& shared, const std::string& map_file, LaserCommand& l,
                           const RunContext& ctx, bool allow_empty) {
  auto& s = l.settings;
  require(!shared.data_dir.empty(),
          "mcl --sensor laser: expected --data naming a CARMEN laser log (e.g. "
          "data/carmen/intel-corrected.log.gz), a robot log with 'laser' records or a ROS bag");
  s.data.data = shared.data_dir;
  require_bag_for_flags(l.bag, shared.data_dir, "mcl --sensor laser");
  s.data.bag = l.bag.options;
  s.data.map = map_file;
  s.proposal = experiments::parse_proposal(shared.method);
  s.implicit_map = shared.map;
  s.particles = static_cast<std::size_t>(shared.particles);
  s.runs = shared.runs;
  s.seed = ctx.seed;
  s.start = experiments::parse_start(shared.init);
  s.odometry_noise = alphas_of(l.alphas, s.odometry_noise);
  s.filter_alphas = alphas_of(l.filter_alphas, s.odometry_noise);
  s.laser.interpolation = experiments::parse_interpolation(l.interpolation);
  s.laser.aggregation = l.aggregation == "cubed-sum" ? robot::BeamAggregation::kCubedSum
                                                     : robot::BeamAggregation::kProduct;
  s.laser_model = experiments::parse_laser_model(l.laser_model);
  s.estimate = experiments::parse_estimate(l.estimate);
  // The shared parameters (nav2's names) mean the same in both models.
  s.beam.z_hit = s.laser.z_hit;
  s.beam.z_rand = s.laser.z_rand;
  s.beam.sigma_hit = s.laser.sigma_hit;
  s.beam.max_beams = s.laser.max_beams;
  s.beam.laser_max_range = s.laser.laser_max_range;
  s.kld.enabled = shared.kld;
  s.kld.kld_err = shared.kld_err;
  s.kld.kld_z = shared.kld_z;
  s.kld.min_particles = static_cast<std::size_t>(shared.min_particles);
  s.kld.max_particles = static_cast<std::size_t>(shared.max_particles);
  s.recovery.enabled = laser_recovery(shared);
  s.recovery.recovery_alpha_slow = shared.recovery_alpha_slow;
  s.recovery.recovery_alpha_fast = shared.recovery_alpha_fast;
  s.recovery.kidnap_probability = shared.kidnap_probability;
  s.keep_tracks = !l.trajectory.empty();
  if (l.params_record && !ctx.quiet) {
    std::string used;
    for (const auto& [key, what] : l.params_record->used)
      used += fmt::format("{}{} ({})", used.empty() ? "" : ", ", key, what);
    fmt::print(stderr, "implicit mcl: --params {}: used {}{}\n", l.params_record->file,
               used.empty() ? "no key" : used,
               l.params_record->overridden.empty()
                   ? ""
                   : fmt::format("; the command line's flags won over {}",
                                 fmt::join(l.params_record->overridden, ", ")));
  }
  const experiments::LaserDataset data = experiments::load_laser_dataset(s.data);
  require(l.alphas.empty() || !data.odometry_recorded(),
          "mcl --sensor laser: --alphas is the noise of odometry synthesised from the reference, "
          "and {} records its odometry; give the filter's model with --filter-alphas",
          data.name);
  Progress bar("laser MCL runs", static_cast<std::size_t>(s.runs), ctx.show_progress());
  const auto r = experiments::run_laser_mcl(s, data, [&](int, int) { bar.tick(); });
  bar.finish();
  write_tum_files(l, r, data);
  nlohmann::json j = experiments::to_json(r);
  if (l.params_record) {
    const auto& pr = *l.params_record;
    nlohmann::json used = nlohmann::json::object();
    for (const auto& [key, what] : pr.used) used[key] = what;
    j["params"] = {{"file", pr.file},
                   {"used", used},
                   {"overridden", pr.overridden},
                   {"not_used", pr.not_used}};
  }
  if (!ctx.out_dir.empty()) {
    OutputFile out(ctx.csv_path("laser_mcl.json"));
    out.stream() << j.dump(2) << "\n";
    out.commit();
  }
  if (ctx.json) {
    print_json(j);
  } else {
    fmt::print(
        "laser MCL on {}: {} proposal, {} model, M = {}{}, {} run{}, {} updates of {} scans\n"
        "  position RMSE {:.3f} ± {:.3f} m (median {:.3f}), heading RMSE {:.4f} rad, lost runs "
        "{}\n"
        "  ESS/M {:.2f}, {:.0f} particles on average, {:.1f} us per update ({:.3f} us per "
        "particle), {:.1f} s\n",
        r.data_name, experiments::to_string(s.proposal), experiments::to_string(s.laser_model),
        s.particles, s.kld.enabled ? " (first; KLD-sampling)" : "", s.runs, s.runs == 1 ? "" : "s",
        r.updates, r.scans_in_log, r.position_rmse_m.mean, r.position_rmse_m.se,
        r.position_rmse_m.median, r.heading_rmse_rad.mean, r.lost_runs, r.ess_fraction.mean,
        r.particles.mean, r.cpu_us_per_update.mean, r.cpu_us_per_update.mean / r.particles.mean,
        r.seconds);
    if (s.start == experiments::StartKind::kGlobal)
      fmt::print("  global starts: success rate {:.2f} within {} updates\n", r.global_success_rate,
                 s.global_updates);
  }
  // A robot log without truth runs, but scores nothing.
  require_scored(j, "mcl", {}, {"scored_updates"}, allow_empty);
}

}  // namespace implicit::app
