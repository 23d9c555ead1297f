// `implicit slam --sensor laser` (cmd_slam_laser.hpp): grid SLAM with the bootstrap,
// GMapping-style or implicit proposal on a CARMEN laser log, over seeds.
#include "cmd_slam_laser.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "implicit/robot/carmen.hpp"
#include "implicit/robot/map_io.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "run_statistics.hpp"
#include "tum_output.hpp"

namespace implicit::app {

void add_grid_slam_options(CLI::App& sub, GridSlamCommand& g) {
  sub.add_option("--sensor", g.sensor,
                 "landmark: point landmarks (synthetic Car Park data or a robot log); laser: grid "
                 "SLAM on a CARMEN laser log (--method bootstrap, gmapping or implicit)")
      ->check(CLI::IsMember({"landmark", "laser"}))
      ->capture_default_str();
  sub.add_option("--alphas", g.alphas,
                 "laser: alpha1..alpha4 of the odometry synthesised from the log's corrected "
                 "poses and of the filter's motion model (default 0.002 each)")
      ->expected(4)
      ->check(in_range(0.0, 10.0));
  sub.add_option("--max-scans", g.max_scans, "laser: use the first N scans of the log (0: all)")
      ->check(in_range(0, 100000000));
  sub.add_option("--map-out", g.map_out,
                 "laser: write the first run's map (its best particle's) as map_server files "
                 "(FILE.yaml and its .pgm)")
      ->check(tum_file_validator());
}

namespace {

struct GridSlamSummaryStat {
  double mean = 0, se = 0;
};

GridSlamSummaryStat grid_slam_stat(const std::vector<double>& v) {
  GridSlamSummaryStat s;
  if (v.empty()) return s;
  s.mean = mean_of(v);
  s.se = v.size() > 1 ? sd_of(v) / std::sqrt(static_cast<double>(v.size())) : 0.0;
  return s;
}

// The map scores of the runs (spec §3.13.5): each fraction may be absent from a run (nothing to
// count), so the statistics are over the runs that have it, and null in JSON when none has.
struct GridSlamMapScores {
  static constexpr const char* kKeys[] = {"map_agreement", "map_occupied_precision",
                                          "map_occupied_recall", "map_f1"};
  std::vector<double> filter[4], odometry[4];
  std::vector<double> reference_cpu, score_cpu;
  double tolerance_m = 0.0;

  static std::optional<double> field(const robot::MapComparison& s, int k) {
    const std::optional<double> f[4] = {s.agreement, s.occupied_precision, s.occupied_recall,
                                        s.occupied_f1};
    return f[k];
  }
  static nlohmann::json value(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  }
  static nlohmann::json mean_or_null(const std::vector<double>& v) {
    return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(mean_of(v));
  }
  // Adds the run's scores to the statistics and to its per_run entry.
  void add(const slam::GridSlamRun& run, nlohmann::json& per_run) {
    if (!run.map_score || !run.odometry_map_score) return;
    tolerance_m = run.map_score->tolerance_m;
    for (int k = 0; k < 4; ++k) {
      const std::optional<double> f = field(*run.map_score, k),
                                  o = field(*run.odometry_map_score, k);
      if (f) filter[k].push_back(*f);
      if (o) odometry[k].push_back(*o);
      per_run[kKeys[k]] = value(f);
    }
    reference_cpu.push_back(run.reference_map_cpu_seconds);
    score_cpu.push_back(run.map_score_cpu_seconds);
  }
  void to_json(nlohmann::json& j) const {
    j["map_tolerance_m"] = tolerance_m;
    for (int k = 0; k < 4; ++k) {
      const auto& v = filter[k];
      const double se = v.size() > 1 ? sd_of(v) / std::sqrt(static_cast<double>(v.size())) : 0.0;
      j[kKeys[k]] = {{"mean", mean_or_null(v)},
                     {"se", v.empty() ? nlohmann::json(nullptr) : nlohmann::json(se)}};
      j[std::string("odometry_") + kKeys[k]] = mean_or_null(odometry[k]);
    }
    j["reference_map_cpu_s"] = mean_or_null(reference_cpu);
    j["map_score_cpu_s"] = mean_or_null(score_cpu);
  }
  std::string text() const {
    const auto f = [](const std::vector<double>& v) {
      return v.empty() ? std::string("n/a") : fmt::format("{:.3f}", mean_of(v));
    };
    return fmt::format(
        "  map against the reference poses' map: agreement {}, occupied precision {}, recall {}, "
        "F1 {} within {:.3f} m (odometry alone: {}, {}, {}, {})\n",
        f(filter[0]), f(filter[1]), f(filter[2]), f(filter[3]), tolerance_m, f(odometry[0]),
        f(odometry[1]), f(odometry[2]), f(odometry[3]));
  }
};

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
                               "data/carmen/intel-corrected.log.gz)");
  if (shared.method != "bootstrap" && shared.method != "gmapping" && shared.method != "implicit")
    throw CLI::ValidationError("--method", fmt::format("--sensor laser: expected bootstrap, "
                                                       "gmapping or implicit (the grid-SLAM "
                                                       "proposals), got '{}'",
                                                       shared.method));
  slam::GridSlamRunOptions o;
  o.proposal = slam::parse_grid_proposal(shared.method);
  // GMapping's default particle count when -M is not given; one run unless --datasets says.
  o.filter.particles =
      g.particles->count() > 0 ? static_cast<std::size_t>(shared.particles) : std::size_t{30};
  const int runs = g.datasets->count() > 0 ? shared.datasets : 1;
  if (!g.alphas.empty()) o.filter.alphas = {g.alphas[0], g.alphas[1], g.alphas[2], g.alphas[3]};
  o.max_scans = static_cast<std::size_t>(g.max_scans);
  o.validate();
  const robot::CarmenLog log = robot::read_carmen(shared.data_dir);
  Progress bar(fmt::format("grid SLAM {} M={}", shared.method, o.filter.particles),
               static_cast<std::size_t>(runs) * 1000, ctx.show_progress());
  std::vector<double> trans, rot, odo_trans, odo_rot, cpu_scan, ess, evals, resamplings;
  std::size_t fallbacks = 0, failures = 0, processed = 0;
  nlohmann::json per_run = nlohmann::json::array();
  GridSlamMapScores maps;
  double log_seconds = 0.0;
  for (int r = 0; r < runs; ++r) {
    slam::GridSlamRunOptions ro = o;
    ro.filter.seed = ctx.seed + static_cast<std::uint64_t>(r);
    ro.data_seed = ctx.seed + static_cast<std::uint64_t>(r);
    std::size_t ticked = 0;
    ro.on_step = [&](std::size_t done, std::size_t total) {
      const std::size_t now = done * 1000 / std::max<std::size_t>(total, 1);
      if (now > ticked) bar.tick(now - ticked);
      ticked = now;
    };
    const slam::GridSlamRun run = slam::run_grid_slam(log, ro);
    if (ticked < 1000) bar.tick(1000 - ticked);
    processed = run.processed;
    if (run.reference.size() > 1)
      log_seconds = std::abs(run.reference.back().time - run.reference.front().time);
    trans.push_back(run.relations.translation_mean);
    rot.push_back(run.relations.rotation_mean_deg);
    odo_trans.push_back(run.odometry_relations.translation_mean);
    odo_rot.push_back(run.odometry_relations.rotation_mean_deg);
    cpu_scan.push_back(1e3 * run.cpu_seconds /
                       static_cast<double>(std::max<std::size_t>(run.processed, 1)));
    ess.push_back(run.mean_ess);
    evals.push_back(run.mean_evaluations);
    resamplings.push_back(static_cast<double>(run.resamplings));
    fallbacks += run.fallbacks;
    failures += run.failures;
    per_run.push_back({{"seed", ro.filter.seed},
                       {"relation_translation_m", run.relations.translation_mean},
                       {"relation_rotation_deg", run.relations.rotation_mean_deg},
                       {"cpu_ms_per_scan", cpu_scan.back()},
                       {"resamplings", run.resamplings}});
    maps.add(run, per_run.back());
    if (r != 0) continue;
    if (!shared.trajectory.empty())
      write_grid_slam_tum(shared.trajectory, "slam --trajectory", run.trajectory);
    if (!shared.truth_trajectory.empty())
      write_grid_slam_tum(shared.truth_trajectory, "slam --truth-trajectory", run.reference);
    if (!g.map_out.empty()) robot::save_map(run.map, g.map_out);
  }
  bar.finish();
  const auto t = grid_slam_stat(trans), rt = grid_slam_stat(rot), cs = grid_slam_stat(cpu_scan);
  nlohmann::json j;
  j["experiment"] = "grid_slam";
  j["data"] = shared.data_dir;
  j["method"] = shared.method;
  j["particles"] = o.filter.particles;
  j["datasets"] = runs;
  j["alphas"] = {o.filter.alphas.alpha1, o.filter.alphas.alpha2, o.filter.alphas.alpha3,
                 o.filter.alphas.alpha4};
  j["seed"] = ctx.seed;
  j["scans_processed"] = processed;
  j["relation_translation_m"] = {{"mean", t.mean}, {"se", t.se}};
  j["relation_rotation_deg"] = {{"mean", rt.mean}, {"se", rt.se}};
  j["odometry_relation_translation_m"] = mean_of(odo_trans);
  j["odometry_relation_rotation_deg"] = mean_of(odo_rot);
  j["cpu_ms_per_scan"] = {{"mean", cs.mean}, {"se", cs.se}};
  j["real_time_factor"] = cs.mean > 0 && processed > 0
                              ? log_seconds / (cs.mean * 1e-3 * static_cast<double>(processed))
                              : 0.0;
  j["ess_fraction"] = mean_of(ess);
  j["evaluations_per_particle_and_scan"] = mean_of(evals);
  j["resamplings_mean"] = mean_of(resamplings);
  j["fallbacks"] = fallbacks;
  j["failures"] = failures;
  maps.to_json(j);
  j["per_run"] = per_run;
  if (ctx.json) {
    print_json(j);
    return;
  }
  fmt::print(
      "grid SLAM on {}: {} proposal, M = {}, {} run{}, {} scans processed\n"
      "  relation error {:.4f} ± {:.4f} m, {:.3f} deg (odometry alone {:.4f} m, {:.3f} deg)\n"
      "  {:.2f} ms CPU per scan, {:.0f}x real time, ESS/M {:.2f}\n",
      shared.data_dir, shared.method, o.filter.particles, runs, runs == 1 ? "" : "s", processed,
      t.mean, t.se, rt.mean, mean_of(odo_trans), mean_of(odo_rot), cs.mean,
      j["real_time_factor"].get<double>(), mean_of(ess));
  fmt::print("{}", maps.text());
}

}  // namespace implicit::app
