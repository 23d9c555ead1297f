// The grid_slam experiment of `implicit reproduce` (beyond the paper): grid SLAM on the bundled
// laser logs by the semi-synthetic protocol (spec §3.13.4), the three proposals on the same
// filter at half of GMapping's particle counts, over seeds. The runs are
// experiments/grid_slam_reproduce.hpp's; this file only lays out the plan.
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cmd_slam_laser.hpp"
#include "experiments/grid_slam_reproduce.hpp"
#include "implicit/core/share_dir.hpp"
#include "reproduce_plan.hpp"

namespace implicit::app {
namespace {

using nlohmann::json;
using slam::GridProposalKind;

struct GridLog {
  const char* name;  ///< for labels
  const char* file;  ///< relative to the share tree's data folder
  std::size_t particles;
  std::size_t max_scans;  ///< 0: all
  bool figure;            ///< its first runs are the figure's main panels
  /// Else, when not empty: its first implicit run is a map panel below them, in the files
  /// grid_slam_<tag>_*.csv (python/plots/figure11.py).
  const char* map_tag = "";
};

/// Whether a run of `kind` on `log` writes figure files: all of the main panels' log, and the
/// implicit run of a log with a map panel.
bool writes_figure(const GridLog& log, GridProposalKind kind) {
  return log.figure || (*log.map_tag != '\0' && kind == GridProposalKind::kImplicit);
}

struct GridPoint {
  GridLog log;
  GridProposalKind proposal;
  int runs;
};

json to_json(const GridPoint& p) {
  return {{"data", p.log.file},
          {"proposal", std::string(slam::to_string(p.proposal))},
          {"particles", p.log.particles},
          {"runs", p.runs},
          {"max_scans", p.log.max_scans}};
}

json run_grid_point(const GridPoint& p, const RunContext& ctx) {
  experiments::GridSlamSettings s;
  // Looked up when the configuration runs, so a missing share tree fails this configuration
  // (with the message naming where it looked), not the whole plan.
  s.data = find_share_dir("data", "IMPLICIT_DATA_DIR") / p.log.file;
  s.run.proposal = p.proposal;
  s.run.filter.particles = p.log.particles;
  s.run.max_scans = p.log.max_scans;
  s.runs = p.runs;
  s.seed = ctx.seed;
  const std::string label =
      fmt::format("grid SLAM {} {} M={}", p.log.name, slam::to_string(p.proposal), p.log.particles);
  Progress bar(label, static_cast<std::size_t>(p.runs) * 1000, ctx.show_progress());
  const bool figure = writes_figure(p.log, p.proposal);
  json j = experiments::run_grid_slam_reproduce(
      s, figure ? ctx.out_dir : std::filesystem::path(),
      figure && p.proposal == GridProposalKind::kImplicit, grid_slam_progress(bar),
      p.log.figure ? std::string("grid_slam") : fmt::format("grid_slam_{}", p.log.map_tag));
  bar.finish();
  // The data as the plan names it: the absolute path of the share tree says nothing portable.
  j["data"] = p.log.file;
  return j;
}

}  // namespace

// Cost, measured (docs/reproducing.md, "Run times"): CPU per processed scan of the implicit and
// GMapping-style proposals is about 2 ms per particle, the bootstrap's a quarter of it.
void add_grid_slam(Plan& plan, bool quick) {
  // Half of the particle counts GMapping's authors used on these logs (docs/reproducing.md,
  // "Grid SLAM"); quick: the first 40 scans of ACES.
  const std::vector<GridLog> logs =
      quick ? std::vector<GridLog>{{"ACES", "carmen/aces-corrected.log.gz", 8, 40, true}}
            : std::vector<GridLog>{{"Intel", "carmen/intel-corrected.log.gz", 8, 0, true},
                                   {"ACES", "carmen/aces-corrected.log.gz", 15, 0, false, "aces"},
                                   {"Freiburg 079", "carmen/freiburg-079-corrected.log.gz", 5, 0,
                                    false, "freiburg-079"}};
  const int runs = quick ? 2 : 10;
  json configurations = json::array();
  for (const GridLog& log : logs)
    for (GridProposalKind kind : {GridProposalKind::kImplicit, GridProposalKind::kScanMatch,
                                  GridProposalKind::kBootstrap}) {
      const GridPoint p{log, kind, runs};
      configurations.push_back(to_json(p));
      // Rough CPU seconds: processed scans (about a third of a whole log's scans pass the gate;
      // 27 of the quick run's 40) times particles times 2 ms (0.5 ms for the bootstrap).
      const double scans = quick ? 27.0 : 500.0;
      const double per_particle = kind == GridProposalKind::kBootstrap ? 5e-4 : 2e-3;
      plan.configs.push_back(
          {"grid_slam",
           fmt::format("grid SLAM {} {} M={}", log.name, slam::to_string(kind), log.particles),
           to_json(p), runs * scans * static_cast<double>(log.particles) * per_particle,
           writes_figure(log, kind),
           [p](const RunContext& ctx) { return run_grid_point(p, ctx); }});
    }
  // The settings every configuration shares: GridSlamRunOptions' defaults, stated for the report.
  const slam::GridSlamRunOptions d;
  const auto& a = d.filter.alphas;
  plan.settings["grid_slam"] = {
      {"configurations", configurations},
      {"runs", runs},
      {"odometry_alphas", {a.alpha1, a.alpha2, a.alpha3, a.alpha4}},
      {"resample_threshold", d.filter.resample_threshold},
      {"linear_update_m", d.filter.gate.linear_update},
      {"angular_update_rad", d.filter.gate.angular_update},
      {"implicit_starts", d.implicit.starts},
      {"map_min_echoes", d.filter.map.min_echoes},
      {"figure_data", quick ? "first run of each proposal on the first 40 scans of ACES"
                            : "first run of each proposal on Intel, M = 8; first implicit run "
                              "on ACES (M = 15) and Freiburg 079 (M = 5)"}};
}

}  // namespace implicit::app
