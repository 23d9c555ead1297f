// The laser_mcl experiment of `implicit reproduce` (beyond the paper): laser MCL on the bundled
// ACES log by the semi-synthetic protocol (spec §3.12), both proposals, tracking from a known
// start against M and global starts. The runs are experiments/laser_reproduce.hpp's; this file
// only lays out the plan.
#include <string>
#include <vector>

#include <fmt/format.h>

#include "experiments/laser_reproduce.hpp"
#include "implicit/core/share_dir.hpp"
#include "reproduce_plan.hpp"

namespace implicit::app {
namespace {

using experiments::ProposalKind;
using experiments::StartKind;
using nlohmann::json;

/// The bundled log, relative to the share tree's data folder.
constexpr const char* kLaserLog = "carmen/aces-corrected.log.gz";

/// Quick: the first 40 updates (of the log's 439), enough for a global start's 10 updates from
/// two places and for the tracks to leave the start.
constexpr std::size_t kQuickUpdates = 40;

struct LaserPoint {
  ProposalKind proposal;
  std::size_t particles;
  int runs;
  StartKind start;
  bool figure;
};

json to_json(const LaserPoint& p, std::size_t max_updates) {
  return {{"proposal", experiments::to_string(p.proposal)},
          {"particles", p.particles},
          {"runs", p.runs},
          {"start", experiments::to_string(p.start)},
          {"data", kLaserLog},
          {"max_updates", max_updates}};
}

json run_point(const LaserPoint& p, std::size_t max_updates, const RunContext& ctx) {
  experiments::LaserMclSettings s;
  // Looked up when the configuration runs, so a missing share tree fails this configuration
  // (with the message naming where it looked), not the whole plan.
  s.data.data = find_share_dir("data", "IMPLICIT_DATA_DIR") / kLaserLog;
  s.data.max_updates = max_updates;
  s.proposal = p.proposal;
  s.particles = p.particles;
  s.runs = p.runs;
  s.start = p.start;
  s.seed = ctx.seed;
  Progress bar(fmt::format("laser {} {} M={}", experiments::to_string(p.start),
                           experiments::to_string(p.proposal), p.particles),
               static_cast<std::size_t>(p.runs), ctx.show_progress());
  json j = experiments::run_laser_reproduce(s, p.figure ? ctx.out_dir : std::filesystem::path(),
                                            [&](int, int) { bar.tick(); });
  bar.finish();
  return j;
}

}  // namespace

// Cost, measured (docs/reproducing.md, "Run times"): the full sweep takes 210 s of CPU time
// (implicit M = 250 alone 73 s, bootstrap M = 5000 45 s), so at most 3.5 min of wall time on 2
// idle cores and about 2 min when both work; it ran in 530 s of wall time on the shared 2-core
// machine at load average 9. No M value or run is cut.
void add_laser_mcl(Plan& plan, bool quick) {
  const std::size_t max_updates = quick ? kQuickUpdates : 0;
  const int runs = quick ? 2 : 10;
  // The figure's tracks: implicit M = 100 and bootstrap M = 1000, in both sizes.
  const std::size_t figure_implicit = 100, figure_bootstrap = 1000;
  std::vector<LaserPoint> points;
  // Quick: the smallest M and the figure's M of each proposal. Measured: 3.1 s of CPU for the
  // quick run with its figure (7.8 s with all four M of each).
  const std::vector<std::size_t> implicit_ms =
      quick ? std::vector<std::size_t>{25, 100} : std::vector<std::size_t>{25, 50, 100, 250};
  const std::vector<std::size_t> bootstrap_ms =
      quick ? std::vector<std::size_t>{250, 1000} : std::vector<std::size_t>{250, 1000, 2500, 5000};
  for (std::size_t m : implicit_ms)
    points.push_back({ProposalKind::kImplicit, m, runs, StartKind::kKnown, m == figure_implicit});
  for (std::size_t m : bootstrap_ms)
    points.push_back({ProposalKind::kBootstrap, m, runs, StartKind::kKnown, m == figure_bootstrap});
  const std::size_t global_implicit = quick ? 200 : 1000, global_bootstrap = quick ? 1000 : 5000;
  points.push_back({ProposalKind::kImplicit, global_implicit, runs, StartKind::kGlobal, false});
  points.push_back({ProposalKind::kBootstrap, global_bootstrap, runs, StartKind::kGlobal, false});
  json tracking = json::array(), global = json::array();
  for (const LaserPoint& p : points) {
    (p.start == StartKind::kKnown ? tracking : global)
        .push_back({{"proposal", experiments::to_string(p.proposal)},
                    {"particles", p.particles},
                    {"runs", p.runs}});
    // Rough CPU seconds per run: the measured CPU time per update and particle (about 65 us
    // implicit, 2 us bootstrap) times the updates (a global run covers 11).
    const double updates = p.start == StartKind::kGlobal ? 11.0 : quick ? 40.0 : 439.0;
    const double per_particle_update = p.proposal == ProposalKind::kImplicit ? 6.5e-5 : 2e-6;
    const double weight = p.runs * (0.02 + updates * p.particles * per_particle_update);
    plan.configs.push_back(
        {"laser_mcl",
         fmt::format("laser {} {} M={}", p.start == StartKind::kKnown ? "tracking" : "global",
                     experiments::to_string(p.proposal), p.particles),
         to_json(p, max_updates), weight, p.figure,
         [p, max_updates](const RunContext& ctx) { return run_point(p, max_updates, ctx); }});
  }
  // The settings every configuration shares: LaserMclSettings' defaults, stated for the report.
  const experiments::LaserMclSettings d;
  const auto& a = d.odometry_noise;
  plan.settings["laser_mcl"] = {
      {"data", kLaserLog},
      {"updates", quick ? json(kQuickUpdates) : json("all")},
      {"tracking", tracking},
      {"global", global},
      {"map_resolution_m", d.data.map_resolution},
      {"map_min_echoes", d.data.map_min_echoes},
      {"update_min_d_m", d.data.update_min_d},
      {"update_min_a_rad", d.data.update_min_a},
      {"odometry_alphas", {a.alpha1, a.alpha2, a.alpha3, a.alpha4}},
      {"likelihood_field",
       {{"z_hit", d.laser.z_hit},
        {"z_rand", d.laser.z_rand},
        {"sigma_hit_m", d.laser.sigma_hit},
        {"max_beams", d.laser.max_beams},
        {"interpolation", experiments::to_string(d.laser.interpolation)}}},
      {"implicit_starts", d.implicit_starts},
      {"initial_std", {d.initial_std_xy, d.initial_std_xy, d.initial_std_heading}},
      {"lost_threshold_m", d.lost_threshold},
      {"global_updates", d.global_updates},
      {"global_success_radius_m", d.global_success_radius},
      {"figure_data", fmt::format("first run of implicit M = {} and bootstrap M = {}",
                                  figure_implicit, figure_bootstrap)}};
}

}  // namespace implicit::app
