#pragma once
// One configuration of `implicit reproduce`'s laser_mcl experiment (beyond the paper): laser MCL
// by the semi-synthetic protocol (laser_mcl.hpp) on a dataset loaded once per process, and the
// files of its figure (python/plots/figure10.py).
//
//   LaserMclSettings s;
//   s.data.data = "data/carmen/aces-corrected.log.gz";
//   s.proposal = ProposalKind::kImplicit;
//   s.particles = 100;
//   nlohmann::json j = run_laser_reproduce(s, "out");  // and out/laser_mcl_*.csv

#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "experiments/laser_mcl.hpp"

namespace implicit::experiments {

/// A dataset from the process-wide cache: the configurations of one reproduce run share one
/// log, and loading it (reading the log, building the map) costs more than a quick run.
struct CachedDataset {
  std::shared_ptr<const LaserDataset> data;
  double load_seconds = 0.0;  ///< wall time of the load (the first one, for a cached dataset)
  bool from_cache = false;
};

/// load_laser_dataset(options), loaded on first use and kept for the process, keyed by every
/// field of `options` (the dataset is a function of them alone, so the cache changes no result).
/// Thread-safe.
CachedDataset cached_laser_dataset(const LaserDataOptions& options);

/// "x_m,y_m,resolution_m" and one line per occupied cell of `map` (its centre): the map of the
/// laser figures.
std::string occupied_cells_csv(const robot::OccupancyGrid& map);

/// The figure's files in `dir` (figure10.py reads them):
///   laser_mcl_map.csv                x_m,y_m,resolution_m: the occupied cells' centres
///   laser_mcl_reference.csv          update,time_s,x_m,y_m,heading_rad: the reference poses
///   laser_mcl_track_<proposal>.csv   update,time_s,x_m,y_m,heading_rad,error_m,particles: the
///                                    first run's estimates (needs keep_tracks)
/// time_s counts from the first update's scan. Each file is written under a temporary name and
/// renamed into place. Throws InvalidArgument naming the file when one cannot be written.
void write_laser_figure_files(const LaserMclResult& r, const LaserDataset& d,
                              const std::filesystem::path& dir);

/// Runs `settings` on the cached dataset; with a non-empty `figure_dir` keeps the tracks and
/// writes the figure's files there. Returns to_json(result) (no tracks) and: "dataset"
/// {load_seconds, from_cache}, "figure_files" (names written), "global_successes" and
/// "updates_to_converge_median" (global starts; null when none succeeded).
nlohmann::json run_laser_reproduce(LaserMclSettings settings,
                                   const std::filesystem::path& figure_dir,
                                   const Progress& progress = {});

}  // namespace implicit::experiments
