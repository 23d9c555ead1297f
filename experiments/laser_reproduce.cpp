// The laser_mcl experiment of `implicit reproduce` (laser_reproduce.hpp): runs on a cached
// dataset, and the figure's CSV files.
#include "experiments/laser_reproduce.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::experiments {

namespace {

/// Every field of the options, exactly (hex floats), so two options share a key only when
/// load_laser_dataset would return the same dataset for both.
std::string cache_key(const LaserDataOptions& o) {
  return fmt::format("{}|{}|{:a}|{:a}|{}|{:a}|{:a}|{}|{}|{}|{}|{}", o.data.string(), o.map.string(),
                     o.map_resolution, o.map_max_range, o.map_min_echoes, o.update_min_d,
                     o.update_min_a, o.max_updates, o.bag.scan_topic, o.bag.odom_topic,
                     o.bag.base_frame, o.bag.laser_frame);
}

/// Written under a temporary name and renamed (OutputFile): a killed run leaves the previous file
/// or none, never half of one that the figure script would draw.
void write_figure_csv(const std::filesystem::path& file, const std::string& text) {
  write_output_file(file, text, "laser_mcl figure");
}

std::string reference_csv(const LaserDataset& d) {
  std::string out = "update,time_s,x_m,y_m,heading_rad\n";
  for (std::size_t k = 0; k < d.reference.size(); ++k) {
    const robot::Pose& p = d.reference[k];
    out += fmt::format("{},{:.3f},{:.4f},{:.4f},{:.5f}\n", k, d.scans[k].time - d.scans[0].time,
                       p(0), p(1), p(2));
  }
  return out;
}

std::string track_csv(const LaserMclResult& r, const LaserDataset& d) {
  const LaserMclRun& run = r.runs.front();
  require(!run.estimates.empty() && run.estimates.size() == run.errors_m.size(),
          "laser_mcl figure: expected the first run's track (keep_tracks), got {} estimates and "
          "{} errors",
          run.estimates.size(), run.errors_m.size());
  require(run.estimates.size() <= d.scans.size(),
          "laser_mcl figure: expected at most {} estimates (one per update), got {}",
          d.scans.size(), run.estimates.size());
  std::string out = "update,time_s,x_m,y_m,heading_rad,error_m,particles\n";
  for (std::size_t k = 0; k < run.estimates.size(); ++k) {
    const robot::Pose& p = run.estimates[k];
    out += fmt::format("{},{:.3f},{:.4f},{:.4f},{:.5f},{:.6g},{}\n", k,
                       d.scans[k].time - d.scans[0].time, p(0), p(1), p(2), run.errors_m[k],
                       r.settings.particles);
  }
  return out;
}

/// The median number of updates to converge over the successful global starts; null when none
/// succeeded (a number would read as a convergence that never happened).
nlohmann::json median_of_converged(const std::vector<LaserMclRun>& runs) {
  std::vector<double> v;
  for (const LaserMclRun& r : runs)
    if (r.global_success) v.push_back(static_cast<double>(r.updates_to_converge));
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

std::string occupied_cells_csv(const robot::OccupancyGrid& map) {
  std::string out = "x_m,y_m,resolution_m\n";
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix)
      if (map.is_occupied(ix, iy)) {
        const Vec<2> c = map.cell_center(ix, iy);
        out += fmt::format("{:.3f},{:.3f},{}\n", c(0), c(1), map.resolution());
      }
  return out;
}

CachedDataset cached_laser_dataset(const LaserDataOptions& options) {
  static std::mutex mutex;
  static std::map<std::string, CachedDataset> cache;
  const std::string key = cache_key(options);
  // Loading under the lock: a second caller waits for the first load instead of repeating it.
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = cache.find(key); it != cache.end()) {
    CachedDataset c = it->second;
    c.from_cache = true;
    return c;
  }
  const auto start = std::chrono::steady_clock::now();
  CachedDataset c;
  c.data = std::make_shared<const LaserDataset>(load_laser_dataset(options));
  c.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  cache.emplace(key, c);
  return c;
}

void write_laser_figure_files(const LaserMclResult& r, const LaserDataset& d,
                              const std::filesystem::path& dir) {
  require(!r.runs.empty(), "laser_mcl figure: expected at least one run, got none");
  // A global run's track starts where the run starts, not at the reference's first update.
  require(r.settings.start == StartKind::kKnown,
          "laser_mcl figure: expected runs from a known start, got a {} start",
          to_string(r.settings.start));
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  require(!ec, "laser_mcl figure: expected a folder '{}' for the figure's files, got: {}",
          dir.string(), ec.message());
  write_figure_csv(dir / "laser_mcl_map.csv", occupied_cells_csv(d.map));
  write_figure_csv(dir / "laser_mcl_reference.csv", reference_csv(d));
  write_figure_csv(dir / fmt::format("laser_mcl_track_{}.csv", to_string(r.settings.proposal)),
                   track_csv(r, d));
}

nlohmann::json run_laser_reproduce(LaserMclSettings settings,
                                   const std::filesystem::path& figure_dir,
                                   const Progress& progress) {
  settings.validate();
  const CachedDataset c = cached_laser_dataset(settings.data);
  const bool figure = !figure_dir.empty();
  settings.keep_tracks = settings.keep_tracks || figure;
  const LaserMclResult r = run_laser_mcl(settings, *c.data, progress);
  nlohmann::json j = to_json(r);
  j["dataset"] = {{"load_seconds", c.load_seconds}, {"from_cache", c.from_cache}};
  nlohmann::json files = nlohmann::json::array();
  if (figure) {
    write_laser_figure_files(r, *c.data, figure_dir);
    files = {"laser_mcl_map.csv", "laser_mcl_reference.csv",
             fmt::format("laser_mcl_track_{}.csv", to_string(settings.proposal))};
  }
  j["figure_files"] = files;
  if (settings.start == StartKind::kGlobal) {
    int successes = 0;
    for (const LaserMclRun& run : r.runs) successes += run.global_success ? 1 : 0;
    j["global_successes"] = successes;
    j["updates_to_converge_median"] = median_of_converged(r.runs);
  }
  return j;
}

}  // namespace implicit::experiments
