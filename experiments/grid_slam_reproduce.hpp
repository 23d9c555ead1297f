#pragma once
// One configuration of `implicit reproduce`'s grid_slam experiment (beyond the paper): grid SLAM
// over seeds (grid_slam.hpp) on a log read once per process, and the files of its figure
// (python/plots/figure11.py).
//
//   GridSlamSettings s;
//   s.data = "data/carmen/intel-corrected.log.gz";
//   s.run.filter.particles = 8;
//   s.runs = 10;
//   nlohmann::json j = run_grid_slam_reproduce(s, "out", true);  // and out/grid_slam_*.csv

#include <filesystem>
#include <memory>
#include <string_view>

#include <nlohmann/json.hpp>

#include "experiments/grid_slam.hpp"

namespace implicit::experiments {

/// read_carmen(path), read on first use and kept for the process (the configurations of one
/// reproduce run share a log; reading Freiburg 079's takes about a second). Thread-safe.
std::shared_ptr<const robot::CarmenLog> cached_carmen_log(const std::filesystem::path& path);

/// The figure's files in `dir` (figure11.py reads them), from r.first (needs keep_first):
///   grid_slam_reference.csv        scan,time_s,x_m,y_m,heading_rad: the corrected poses at the
///                                  processed scans
///   grid_slam_track_<method>.csv   scan,time_s,x_m,y_m,heading_rad,relation_error_m: the first
///                                  run's best trajectory and the translational error of the
///                                  relation ending at each scan (empty at the first scan)
///   grid_slam_map.csv              x_m,y_m,resolution_m: the occupied cells of the first run's
///                                  map (only when `with_map`)
/// time_s counts from the first processed scan; `prefix` replaces "grid_slam" in the names (the
/// map panels of the other logs: "grid_slam_aces", ...). Each file is written under a temporary
/// name and renamed into place. Throws InvalidArgument naming the file when one cannot be
/// written.
void write_grid_slam_figure_files(const GridSlamResult& r, const std::filesystem::path& dir,
                                  bool with_map, std::string_view prefix = "grid_slam");

/// Runs `settings` on the cached log. With a non-empty `figure_dir` keeps the first run and
/// writes its track (and the map when `with_map`) there, named by `prefix`. Returns
/// to_json(result) and "figure_files" (the names written) and "read_seconds" (reading the log;
/// about 0 when it came from the cache).
nlohmann::json run_grid_slam_reproduce(GridSlamSettings settings,
                                       const std::filesystem::path& figure_dir, bool with_map,
                                       const GridSlamProgress& progress = {},
                                       std::string_view prefix = "grid_slam");

}  // namespace implicit::experiments
