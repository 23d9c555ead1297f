// Grid SLAM over seeds (grid_slam.hpp).
#include "experiments/grid_slam.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "implicit/core/error.hpp"

namespace implicit::experiments {

namespace {

GridSlamStat stat_of(const std::vector<GridSlamRunRecord>& runs, double GridSlamRunRecord::*field) {
  GridSlamStat s;
  const double n = static_cast<double>(runs.size());
  if (runs.empty()) return s;
  for (const auto& r : runs) s.mean += r.*field;
  s.mean /= n;
  if (runs.size() > 1) {
    double ss = 0.0;
    for (const auto& r : runs) ss += (r.*field - s.mean) * (r.*field - s.mean);
    s.se = std::sqrt(ss / (n - 1.0)) / std::sqrt(n);
  }
  return s;
}

GridSlamRunRecord record_of(const slam::GridSlamRun& run, std::uint64_t seed) {
  GridSlamRunRecord r;
  r.seed = seed;
  r.relation_translation_m = run.relations.translation_mean;
  r.relation_rotation_deg = run.relations.rotation_mean_deg;
  r.odometry_translation_m = run.odometry_relations.translation_mean;
  r.odometry_rotation_deg = run.odometry_relations.rotation_mean_deg;
  r.cpu_ms_per_scan =
      1e3 * run.cpu_seconds / static_cast<double>(std::max<std::size_t>(run.processed, 1));
  r.ess_fraction = run.mean_ess;
  r.evaluations = run.mean_evaluations;
  r.resamplings = run.resamplings;
  r.fallbacks = run.fallbacks;
  r.failures = run.failures;
  return r;
}

/// The summaries over the runs (records already in place).
void summarise(GridSlamResult& result) {
  const auto& runs = result.runs;
  result.relation_translation_m = stat_of(runs, &GridSlamRunRecord::relation_translation_m);
  result.relation_rotation_deg = stat_of(runs, &GridSlamRunRecord::relation_rotation_deg);
  result.cpu_ms_per_scan = stat_of(runs, &GridSlamRunRecord::cpu_ms_per_scan);
  result.odometry_translation_m = stat_of(runs, &GridSlamRunRecord::odometry_translation_m).mean;
  result.odometry_rotation_deg = stat_of(runs, &GridSlamRunRecord::odometry_rotation_deg).mean;
  result.ess_fraction = stat_of(runs, &GridSlamRunRecord::ess_fraction).mean;
  result.evaluations = stat_of(runs, &GridSlamRunRecord::evaluations).mean;
  for (const auto& r : runs) {
    result.resamplings += static_cast<double>(r.resamplings);
    result.fallbacks += r.fallbacks;
    result.failures += r.failures;
  }
  if (!runs.empty()) result.resamplings /= static_cast<double>(runs.size());
  const double cpu_seconds =
      result.cpu_ms_per_scan.mean * 1e-3 * static_cast<double>(result.scans_processed);
  result.real_time_factor = cpu_seconds > 0.0 ? result.log_seconds / cpu_seconds : 0.0;
}

}  // namespace

void GridSlamSettings::validate() const {
  require(runs >= 1, "grid SLAM: expected at least one run, got {}", runs);
  run.validate();
}

GridSlamResult run_grid_slam_experiment(const GridSlamSettings& settings,
                                        const robot::CarmenLog& log,
                                        const GridSlamProgress& progress) {
  settings.validate();
  GridSlamResult result;
  result.settings = settings;
  result.settings.run.on_step = nullptr;  // a copy of the caller's callback is not a result
  for (int k = 0; k < settings.runs; ++k) {
    slam::GridSlamRunOptions o = settings.run;
    const std::uint64_t seed = settings.seed + static_cast<std::uint64_t>(k);
    o.filter.seed = seed;
    o.data_seed = seed;
    if (progress)
      o.on_step = [&](std::size_t done, std::size_t total) { progress(k, done, total); };
    slam::GridSlamRun run = slam::run_grid_slam(log, o);
    result.scans_processed = run.processed;
    if (run.reference.size() > 1)
      result.log_seconds = std::abs(run.reference.back().time - run.reference.front().time);
    result.runs.push_back(record_of(run, seed));
    if (k == 0 && settings.keep_first) result.first = std::move(run);
  }
  summarise(result);
  return result;
}

nlohmann::json to_json(const GridSlamResult& r) {
  const slam::GridSlamRunOptions& o = r.settings.run;
  const auto stat = [](const GridSlamStat& s) {
    return nlohmann::json{{"mean", s.mean}, {"se", s.se}};
  };
  nlohmann::json j;
  j["experiment"] = "grid_slam";
  j["data"] = r.settings.data.string();
  j["method"] = std::string(slam::to_string(o.proposal));
  j["particles"] = o.filter.particles;
  j["datasets"] = r.settings.runs;
  j["alphas"] = {o.filter.alphas.alpha1, o.filter.alphas.alpha2, o.filter.alphas.alpha3,
                 o.filter.alphas.alpha4};
  j["seed"] = r.settings.seed;
  j["scans_processed"] = r.scans_processed;
  j["relation_translation_m"] = stat(r.relation_translation_m);
  j["relation_rotation_deg"] = stat(r.relation_rotation_deg);
  j["odometry_relation_translation_m"] = r.odometry_translation_m;
  j["odometry_relation_rotation_deg"] = r.odometry_rotation_deg;
  j["cpu_ms_per_scan"] = stat(r.cpu_ms_per_scan);
  j["real_time_factor"] = r.real_time_factor;
  j["ess_fraction"] = r.ess_fraction;
  j["evaluations_per_particle_and_scan"] = r.evaluations;
  j["resamplings_mean"] = r.resamplings;
  j["fallbacks"] = r.fallbacks;
  j["failures"] = r.failures;
  nlohmann::json per_run = nlohmann::json::array();
  for (const auto& run : r.runs)
    per_run.push_back({{"seed", run.seed},
                       {"relation_translation_m", run.relation_translation_m},
                       {"relation_rotation_deg", run.relation_rotation_deg},
                       {"cpu_ms_per_scan", run.cpu_ms_per_scan},
                       {"resamplings", run.resamplings}});
  j["per_run"] = per_run;
  return j;
}

}  // namespace implicit::experiments
