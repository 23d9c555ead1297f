// `implicit slam --sensor laser` (cmd_slam_laser.hpp): grid SLAM with the bootstrap,
// GMapping-style or implicit proposal on a CARMEN laser log, over seeds.
#include "cmd_slam_laser.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "experiments/choices.hpp"
#include "experiments/grid_slam.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/map_io.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/pose_graph.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "tum_output.hpp"

namespace implicit::app {

experiments::GridSlamProgress grid_slam_progress(Progress& bar) {
  auto ticked = std::make_shared<std::size_t>(0);
  return [&bar, ticked](int run, std::size_t done, std::size_t total) {
    const std::size_t now =
        static_cast<std::size_t>(run) * 1000 + done * 1000 / std::max<std::size_t>(total, 1);
    if (now > *ticked) bar.tick(now - *ticked);
    *ticked = std::max(*ticked, now);
  };
}

void add_grid_slam_options(CLI::App& sub, GridSlamCommand& g) {
  sub.add_option("--sensor", g.sensor,
                 experiments::sensors().help() + " (laser: grid SLAM, --method " +
                     experiments::grid_slam_methods().quoted() + ")")
      ->check(CLI::IsMember(experiments::sensors().names()))
      ->capture_default_str();
  g.laser_only = {
      sub.add_option("--alphas", g.alphas,
                     "laser: alpha1..alpha4 of the odometry synthesised from the log's corrected "
                     "poses and of the filter's motion model (a ROS bag: of the filter's model "
                     "only; default 0.002 each)")
          ->expected(4)
          ->check(in_range(0.0, 10.0)),
      sub.add_option("--max-scans", g.max_scans, "laser: use the first N scans of the log (0: all)")
          ->check(in_range(0, 100000000)),
      sub.add_option("--map-min-echoes", g.map_min_echoes,
                     "laser: a cell where beams of N scans ended is occupied in the particles' "
                     "maps, whatever its log-odds (0: log-odds alone; default 1)")
          ->check(in_range(0, 255)),
      sub.add_option("--map-out", g.map_out,
                     "laser: write the first run's map (its best particle's) as map_server files "
                     "(FILE.yaml and its .pgm)")
          ->check(tum_file_validator()),
      sub.add_option("--g2o", g.g2o,
                     "laser: write the first run's pose graph as a g2o file (its trajectory as "
                     "VERTEX_SE2, the odometry between consecutive scans as EDGE_SE2 with the "
                     "information of the filter's motion noise), for post-optimisation")
          ->check(tum_file_validator()),
  };
  add_bag_flags(sub, g.bag);
  g.laser_only.insert(g.laser_only.end(), g.bag.given.begin(), g.bag.given.end());
}

namespace {

/// "0.123" or "n/a" (nothing counted).
std::string fraction_text(const std::optional<double>& v) {
  return v ? fmt::format("{:.3f}", *v) : std::string("n/a");
}
std::string fraction_text(const std::optional<experiments::GridSlamStat>& v) {
  return v ? fmt::format("{:.3f}", v->mean) : std::string("n/a");
}

/// The relation errors, or "n/a" without a reference (recorded odometry): never a 0 that reads
/// as a score.
std::string relation_text(const experiments::GridSlamResult& r) {
  if (!r.has_reference) return "n/a (no reference poses)";
  return fmt::format("{:.4f} ± {:.4f} m, {:.3f} deg (odometry alone {:.4f} m, {:.3f} deg)",
                     r.relation_translation_m.mean, r.relation_translation_m.se,
                     r.relation_rotation_deg.mean, r.odometry_translation_m,
                     r.odometry_rotation_deg);
}

void print_grid_slam_text(const experiments::GridSlamResult& r, const std::string& data) {
  const auto& o = r.settings.run;
  fmt::print(
      "grid SLAM on {}: {} proposal, M = {}, {} run{}, {} scans processed, {} odometry\n"
      "  relation error {}\n"
      "  trajectory error after SE(2) alignment {} m (odometry alone {} m)\n"
      "  {:.2f} ms CPU per scan, {:.0f}x real time, ESS/M {:.2f}\n",
      data, slam::to_string(o.proposal), o.filter.particles, r.settings.runs,
      r.settings.runs == 1 ? "" : "s", r.scans_processed,
      o.odometry == slam::GridOdometrySource::kRecorded ? "recorded" : "synthesised",
      relation_text(r), fraction_text(r.ate_m), fraction_text(r.odometry_ate_m),
      r.cpu_ms_per_scan.mean, r.real_time_factor, r.ess_fraction);
  if (!o.score_map || !r.has_reference) return;  // no reference map to score against
  const auto& m = r.odometry_map;
  fmt::print(
      "  map against the reference poses' map: agreement {}, occupied precision {}, recall {}, "
      "F1 {} within {:.3f} m (odometry alone: {}, {}, {}, {})\n",
      fraction_text(r.map_agreement), fraction_text(r.map_precision), fraction_text(r.map_recall),
      fraction_text(r.map_f1), r.map_tolerance_m, fraction_text(m.agreement),
      fraction_text(m.precision), fraction_text(m.recall), fraction_text(m.f1));
}

void write_grid_slam_tum(const std::string& file, std::string_view flag,
                         const std::vector<slam::GridSlamPose>& poses) {
  // The bundled logs' scan times are not always increasing (Intel's go back once): TUM needs
  // increasing times, so a pose not after the previous one is left out, and said.
  TumTrack track;
  double last = -std::numeric_limits<double>::infinity();
  std::size_t dropped = 0;
  for (const auto& p : poses) {
    if (!(p.time > last)) {
      ++dropped;
      continue;
    }
    track.add(p.time, p.pose);
    last = p.time;
  }
  if (dropped > 0)
    fmt::print(stderr,
               "implicit slam: {} {}: {} pose(s) left out, their scan time not after the "
               "previous scan's\n",
               flag, file, dropped);
  track.write(file, flag);
}

/// The poses of a trajectory, without their times (a pose graph's vertices).
std::vector<robot::Pose> grid_slam_poses(const std::vector<slam::GridSlamPose>& trajectory) {
  std::vector<robot::Pose> poses;
  for (const auto& p : trajectory) poses.push_back(p.pose);
  return poses;
}

}  // namespace

void run_grid_slam_command(const SlamSettings& shared, const GridSlamCommand& g,
                           const RunContext& ctx) {
  // Flag combinations that cannot work are a bad command line (exit 2), like CLI11's own checks.
  for (const CLI::Option* o : g.landmark_only)
    if (o->count() > 0)
      throw CLI::ValidationError(
          o->get_name(), "applies to landmark SLAM (--sensor landmark), not to --sensor laser");
  if (shared.data_dir.empty())
    throw CLI::ValidationError("--data",
                               "--sensor laser needs --data naming a CARMEN laser log (e.g. "
                               "data/carmen/intel-corrected.log.gz) or a ROS bag");
  // A bag's odometry is the filter's input as recorded: there are no reference poses.
  const bool bag = robot::is_bag(shared.data_dir);
  if (bag && !shared.truth_trajectory.empty())
    throw CLI::ValidationError("--truth-trajectory",
                               "a ROS bag as --data has no reference poses to write (its odometry "
                               "is the filter's input)");
  if (shared.method != "bootstrap" && shared.method != "gmapping" && shared.method != "implicit")
    throw CLI::ValidationError("--method", fmt::format("--sensor laser: expected bootstrap, "
                                                       "gmapping or implicit (the grid-SLAM "
                                                       "proposals), got '{}'",
                                                       shared.method));
  experiments::GridSlamSettings settings;
  slam::GridSlamRunOptions& o = settings.run;
  settings.data = shared.data_dir;
  o.proposal = slam::parse_grid_proposal(shared.method);
  // GMapping's default particle count when -M is not given; one run unless --datasets says.
  o.filter.particles =
      g.particles->count() > 0 ? static_cast<std::size_t>(shared.particles) : std::size_t{30};
  settings.runs = g.datasets->count() > 0 ? shared.datasets : 1;
  settings.seed = ctx.seed;
  settings.keep_first = true;  // its trajectory and map for the files below
  if (!g.alphas.empty()) o.filter.alphas = {g.alphas[0], g.alphas[1], g.alphas[2], g.alphas[3]};
  o.max_scans = static_cast<std::size_t>(g.max_scans);
  if (g.map_min_echoes >= 0) o.filter.map.min_echoes = g.map_min_echoes;
  settings.validate();
  require_bag_for_flags(g.bag, shared.data_dir, "slam --sensor laser");
  if (bag) o.odometry = slam::GridOdometrySource::kRecorded;
  const robot::CarmenLog log = bag ? robot::read_bag_laser_log(shared.data_dir, g.bag.options).log
                                   : robot::read_carmen(shared.data_dir);
  // Progress in thousandths of each run (the scans a run processes are known once it starts).
  Progress bar(fmt::format("grid SLAM {} M={}", shared.method, o.filter.particles),
               static_cast<std::size_t>(settings.runs) * 1000, ctx.show_progress());
  const experiments::GridSlamResult r =
      experiments::run_grid_slam_experiment(settings, log, grid_slam_progress(bar));
  bar.finish();
  const slam::GridSlamRun& first = *r.first;
  if (!shared.trajectory.empty())
    write_grid_slam_tum(shared.trajectory, "slam --trajectory", first.trajectory);
  if (!shared.truth_trajectory.empty())
    write_grid_slam_tum(shared.truth_trajectory, "slam --truth-trajectory", first.reference);
  if (!g.map_out.empty()) robot::save_map(first.map, g.map_out);
  if (!g.g2o.empty())
    robot::write_g2o(
        g.g2o,
        robot::odometry_pose_graph(grid_slam_poses(first.trajectory), first.odometry,
                                   robot::OdometryModel(o.filter.alphas, o.filter.floor_std)),
        "slam --g2o");
  nlohmann::json j = experiments::to_json(r);
  j["data"] = shared.data_dir;  // as given on the command line
  if (ctx.json) {
    print_json(j);
    return;
  }
  print_grid_slam_text(r, shared.data_dir);
}

}  // namespace implicit::app
