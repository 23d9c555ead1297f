// Grid SLAM over seeds (grid_slam.hpp).
#include "experiments/grid_slam.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <optional>

#include "implicit/core/error.hpp"

namespace implicit::experiments {

namespace {

GridSlamStat stat_of(const std::vector<double>& v) {
  GridSlamStat s;
  const double n = static_cast<double>(v.size());
  if (v.empty()) return s;
  for (double x : v) s.mean += x;
  s.mean /= n;
  if (v.size() > 1) {
    double ss = 0.0;
    for (double x : v) ss += (x - s.mean) * (x - s.mean);
    s.se = std::sqrt(ss / (n - 1.0)) / std::sqrt(n);
  }
  return s;
}

GridSlamStat stat_of(const std::vector<GridSlamRunRecord>& runs, double GridSlamRunRecord::*field) {
  std::vector<double> v;
  for (const auto& r : runs) v.push_back(r.*field);
  return stat_of(v);
}

/// Over the runs that have the value; nullopt when none has.
std::optional<GridSlamStat> stat_of_present(
    const std::vector<GridSlamRunRecord>& runs,
    const std::function<std::optional<double>(const GridSlamRunRecord&)>& field) {
  std::vector<double> v;
  for (const auto& r : runs)
    if (const auto x = field(r)) v.push_back(*x);
  if (v.empty()) return std::nullopt;
  return stat_of(v);
}

std::optional<double> mean_of_present(
    const std::vector<GridSlamRunRecord>& runs,
    const std::function<std::optional<double>(const GridSlamRunRecord&)>& field) {
  const auto s = stat_of_present(runs, field);
  return s ? std::optional<double>(s->mean) : std::nullopt;
}

MapFractions fractions_of(const std::optional<robot::MapComparison>& c) {
  if (!c) return {};
  return {c->agreement, c->occupied_precision, c->occupied_recall, c->occupied_f1};
}

GridSlamRunRecord record_of(const slam::GridSlamRun& run, std::uint64_t seed) {
  GridSlamRunRecord r;
  r.seed = seed;
  r.has_reference = run.has_reference;
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
  r.ate_m = run.ate_m;
  r.odometry_ate_m = run.odometry_ate_m;
  r.map = fractions_of(run.map_score);
  r.odometry_map = fractions_of(run.odometry_map_score);
  r.reference_map_cpu_s = run.reference_map_cpu_seconds;
  r.map_score_cpu_s = run.map_score_cpu_seconds;
  return r;
}

/// The map scores over the runs.
void summarise_maps(GridSlamResult& result) {
  const auto& runs = result.runs;
  using R = GridSlamRunRecord;
  result.map_agreement = stat_of_present(runs, [](const R& r) { return r.map.agreement; });
  result.map_precision = stat_of_present(runs, [](const R& r) { return r.map.precision; });
  result.map_recall = stat_of_present(runs, [](const R& r) { return r.map.recall; });
  result.map_f1 = stat_of_present(runs, [](const R& r) { return r.map.f1; });
  auto& o = result.odometry_map;
  o.agreement = mean_of_present(runs, [](const R& r) { return r.odometry_map.agreement; });
  o.precision = mean_of_present(runs, [](const R& r) { return r.odometry_map.precision; });
  o.recall = mean_of_present(runs, [](const R& r) { return r.odometry_map.recall; });
  o.f1 = mean_of_present(runs, [](const R& r) { return r.odometry_map.f1; });
  result.reference_map_cpu_s = stat_of(runs, &R::reference_map_cpu_s).mean;
  result.map_score_cpu_s = stat_of(runs, &R::map_score_cpu_s).mean;
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
  result.ate_m = stat_of_present(runs, [](const GridSlamRunRecord& r) { return r.ate_m; });
  result.odometry_ate_m =
      mean_of_present(runs, [](const GridSlamRunRecord& r) { return r.odometry_ate_m; });
  summarise_maps(result);
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
    if (run.trajectory.size() > 1)
      result.log_seconds = std::abs(run.trajectory.back().time - run.trajectory.front().time);
    result.has_reference = run.has_reference;
    result.runs.push_back(record_of(run, seed));
    if (run.map_score) result.map_tolerance_m = run.map_score->tolerance_m;
    if (k == 0 && settings.keep_first) result.first = std::move(run);
  }
  summarise(result);
  return result;
}

nlohmann::json to_json(const GridSlamResult& r) {
  using nlohmann::json;
  const slam::GridSlamRunOptions& o = r.settings.run;
  const auto stat = [](const GridSlamStat& s) { return json{{"mean", s.mean}, {"se", s.se}}; };
  // A value nothing was counted for is null, never a number that reads as a result.
  const auto maybe = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  const auto maybe_stat = [&](const std::optional<GridSlamStat>& s) {
    return s ? stat(*s) : json{{"mean", nullptr}, {"se", nullptr}};
  };
  json j;
  j["experiment"] = "grid_slam";
  j["data"] = r.settings.data.string();
  j["method"] = std::string(slam::to_string(o.proposal));
  j["particles"] = o.filter.particles;
  j["datasets"] = r.settings.runs;
  j["alphas"] = {o.filter.alphas.alpha1, o.filter.alphas.alpha2, o.filter.alphas.alpha3,
                 o.filter.alphas.alpha4};
  j["seed"] = r.settings.seed;
  j["map_min_echoes"] = o.filter.map.min_echoes;
  j["odometry"] = o.odometry == slam::GridOdometrySource::kRecorded ? "recorded" : "synthesised";
  j["scans_processed"] = r.scans_processed;
  // Without a reference (recorded odometry) the relation errors were not computed: null.
  const auto scored = [&](double v) {
    return maybe(r.has_reference ? std::optional(v) : std::nullopt);
  };
  const auto scored_stat = [&](const GridSlamStat& s) {
    return maybe_stat(r.has_reference ? std::optional(s) : std::nullopt);
  };
  j["relation_translation_m"] = scored_stat(r.relation_translation_m);
  j["relation_rotation_deg"] = scored_stat(r.relation_rotation_deg);
  j["odometry_relation_translation_m"] = scored(r.odometry_translation_m);
  j["odometry_relation_rotation_deg"] = scored(r.odometry_rotation_deg);
  j["ate_m"] = maybe_stat(r.ate_m);
  j["odometry_ate_m"] = maybe(r.odometry_ate_m);
  j["cpu_ms_per_scan"] = stat(r.cpu_ms_per_scan);
  j["real_time_factor"] = r.real_time_factor;
  j["ess_fraction"] = r.ess_fraction;
  j["evaluations_per_particle_and_scan"] = r.evaluations;
  j["resamplings_mean"] = r.resamplings;
  j["fallbacks"] = r.fallbacks;
  j["failures"] = r.failures;
  j["map_tolerance_m"] = r.has_reference ? json(r.map_tolerance_m) : json(nullptr);
  j["map_agreement"] = maybe_stat(r.map_agreement);
  j["map_occupied_precision"] = maybe_stat(r.map_precision);
  j["map_occupied_recall"] = maybe_stat(r.map_recall);
  j["map_f1"] = maybe_stat(r.map_f1);
  j["odometry_map_agreement"] = maybe(r.odometry_map.agreement);
  j["odometry_map_occupied_precision"] = maybe(r.odometry_map.precision);
  j["odometry_map_occupied_recall"] = maybe(r.odometry_map.recall);
  j["odometry_map_f1"] = maybe(r.odometry_map.f1);
  j["reference_map_cpu_s"] = r.reference_map_cpu_s;
  j["map_score_cpu_s"] = r.map_score_cpu_s;
  json per_run = json::array();
  for (const auto& run : r.runs) {
    const auto run_scored = [&](double v) {
      return maybe(run.has_reference ? std::optional(v) : std::nullopt);
    };
    per_run.push_back({{"seed", run.seed},
                       {"relation_translation_m", run_scored(run.relation_translation_m)},
                       {"relation_rotation_deg", run_scored(run.relation_rotation_deg)},
                       {"ate_m", maybe(run.ate_m)},
                       {"cpu_ms_per_scan", run.cpu_ms_per_scan},
                       {"resamplings", run.resamplings},
                       {"map_agreement", maybe(run.map.agreement)},
                       {"map_occupied_precision", maybe(run.map.precision)},
                       {"map_occupied_recall", maybe(run.map.recall)},
                       {"map_f1", maybe(run.map.f1)}});
  }
  j["per_run"] = per_run;
  return j;
}

}  // namespace implicit::experiments
