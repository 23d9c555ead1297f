#pragma once
// Grid SLAM over seeds on one CARMEN laser log: what `implicit slam --sensor laser` and the
// grid_slam experiment of `implicit reproduce` run (spec §3.13.4). Each run is one
// slam::run_grid_slam with seed s for both the synthesised odometry and the filter's draws.
//
//   GridSlamSettings s;
//   s.data = "data/carmen/intel-corrected.log.gz";
//   s.run.proposal = slam::GridProposalKind::kImplicit;
//   s.run.filter.particles = 8;
//   s.runs = 10;                                  // seeds 1..10
//   GridSlamResult r = run_grid_slam_experiment(s, robot::read_carmen(s.data));
//   r.relation_translation_m.mean;                // [m], with its standard error .se
//   fmt::print("{}\n", to_json(r).dump());

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "implicit/robot/carmen.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"

namespace implicit::experiments {

struct GridSlamSettings {
  std::filesystem::path data;  ///< the CARMEN log (named in the result)
  /// One run's options; its seeds (filter.seed, data_seed) and on_step are set per run.
  slam::GridSlamRunOptions run;
  int runs = 1;             ///< seeds seed, seed + 1, ...
  std::uint64_t seed = 1;   ///< the first run's
  bool keep_first = false;  ///< keep the first run whole (trajectory, reference, map)
  void validate() const;
};

/// Agreement, occupied precision, recall and F1 of a map score (robot::MapComparison).
struct MapFractions {
  std::optional<double> agreement, precision, recall, f1;
};

/// One run's numbers (the trajectory and map only for the first run, in GridSlamResult::first).
struct GridSlamRunRecord {
  std::uint64_t seed = 0;
  /// False with recorded odometry (no reference): the relation errors below are then not
  /// scores, and to_json writes them as null.
  bool has_reference = true;
  double relation_translation_m = 0.0, relation_rotation_deg = 0.0;
  double odometry_translation_m = 0.0, odometry_rotation_deg = 0.0;
  double cpu_ms_per_scan = 0.0;
  double ess_fraction = 0.0;  ///< mean N_eff / N before resampling
  double evaluations = 0.0;   ///< scan-likelihood evaluations per particle and scan
  std::size_t resamplings = 0, fallbacks = 0, failures = 0;
  /// The absolute trajectory errors after SE(2) alignment (GridSlamRun::ate_m).
  std::optional<double> ate_m, odometry_ate_m;
  /// The map scores (spec §3.13.5), each absent when the run had nothing to count (or no score).
  MapFractions map, odometry_map;
  double reference_map_cpu_s = 0.0, map_score_cpu_s = 0.0;
};

/// Mean and standard error (sample sd / sqrt(runs); 0 for one run) over the runs.
struct GridSlamStat {
  double mean = 0.0, se = 0.0;
};

struct GridSlamResult {
  GridSlamSettings settings;
  std::size_t scans_processed =
      0;                      ///< per run (the same for every seed: the gate is the reference's)
  double log_seconds = 0.0;   ///< time spanned by the processed scans
  bool has_reference = true;  ///< false with recorded odometry: the relation errors are not scores
  std::vector<GridSlamRunRecord> runs;
  GridSlamStat relation_translation_m, relation_rotation_deg, cpu_ms_per_scan;
  double odometry_translation_m = 0.0, odometry_rotation_deg = 0.0;  ///< means over the runs
  double ess_fraction = 0.0, evaluations = 0.0, resamplings = 0.0;   ///< means over the runs
  std::size_t fallbacks = 0, failures = 0;                           ///< sums over the runs
  /// The log's span over the mean CPU time of a run: how much faster than real time.
  double real_time_factor = 0.0;
  /// Over the runs that have each value (std::nullopt when none has): the ATE and the map
  /// fractions of the filter with their standard errors, and the odometry's means.
  std::optional<GridSlamStat> ate_m;
  std::optional<double> odometry_ate_m;
  std::optional<GridSlamStat> map_agreement, map_precision, map_recall, map_f1;
  MapFractions odometry_map;
  double map_tolerance_m = 0.0;
  double reference_map_cpu_s = 0.0, map_score_cpu_s = 0.0;  ///< means over the runs
  std::optional<slam::GridSlamRun> first;  ///< the first run, when settings.keep_first
};

/// Called after each processed scan with (run, scans done in it, scans it will process).
using GridSlamProgress = std::function<void(int, std::size_t, std::size_t)>;

/// Runs settings.runs filters on `log` in turn (each filter uses the threads itself). Throws
/// InvalidArgument for invalid settings or a log without scans.
GridSlamResult run_grid_slam_experiment(const GridSlamSettings& settings,
                                        const robot::CarmenLog& log,
                                        const GridSlamProgress& progress = {});

/// The result by name: the keys of `implicit slam --sensor laser --json` (docs/cli.md).
nlohmann::json to_json(const GridSlamResult& r);

}  // namespace implicit::experiments
