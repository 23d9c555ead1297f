// The grid_slam experiment of `implicit reproduce` (grid_slam_reproduce.hpp): runs on a cached
// log, and the figure's CSV files.
#include "experiments/grid_slam_reproduce.hpp"

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "experiments/laser_reproduce.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"

namespace implicit::experiments {

namespace {

std::string grid_reference_csv(const slam::GridSlamRun& run) {
  std::string out = "scan,time_s,x_m,y_m,heading_rad\n";
  const double t0 = run.reference.empty() ? 0.0 : run.reference.front().time;
  for (std::size_t k = 0; k < run.reference.size(); ++k) {
    const robot::Pose& p = run.reference[k].pose;
    out += fmt::format("{},{:.3f},{:.4f},{:.4f},{:.5f}\n", k, run.reference[k].time - t0, p(0),
                       p(1), p(2));
  }
  return out;
}

std::string grid_track_csv(const slam::GridSlamRun& run) {
  require(run.trajectory.size() == run.reference.size(),
          "grid_slam figure: expected one estimate per processed scan ({}), got {}",
          run.reference.size(), run.trajectory.size());
  // The error of relation k - 1 -> k at row k; every relation has both poses (they are matched
  // by index), so `used` is 0, 1, ... and the check below only guards that invariant.
  const auto& rel = run.relations;
  std::vector<std::string> error(run.trajectory.size());
  for (std::size_t i = 0; i < rel.used.size(); ++i) {
    const std::size_t row = rel.used[i] + 1;
    require(row < error.size(), "grid_slam figure: relation {} ends after the last scan ({})",
            rel.used[i], error.size());
    error[row] = fmt::format("{:.6g}", rel.translation[i]);
  }
  std::string out = "scan,time_s,x_m,y_m,heading_rad,relation_error_m\n";
  const double t0 = run.reference.empty() ? 0.0 : run.reference.front().time;
  for (std::size_t k = 0; k < run.trajectory.size(); ++k) {
    const robot::Pose& p = run.trajectory[k].pose;
    out += fmt::format("{},{:.3f},{:.4f},{:.4f},{:.5f},{}\n", k, run.reference[k].time - t0, p(0),
                       p(1), p(2), error[k]);
  }
  return out;
}

// The names of the figure's files: reference, track, and map when `with_map`.
std::vector<std::string> grid_slam_figure_files(const GridSlamResult& r, bool with_map,
                                                std::string_view prefix) {
  std::vector<std::string> names{
      fmt::format("{}_reference.csv", prefix),
      fmt::format("{}_track_{}.csv", prefix, slam::to_string(r.settings.run.proposal))};
  if (with_map) names.push_back(fmt::format("{}_map.csv", prefix));
  return names;
}

}  // namespace

std::shared_ptr<const robot::CarmenLog> cached_carmen_log(const std::filesystem::path& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const robot::CarmenLog>> cache;
  // Reading under the lock: a second caller waits for the first read instead of repeating it.
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[path.string()];
  if (!slot) slot = std::make_shared<const robot::CarmenLog>(robot::read_carmen(path));
  return slot;
}

void write_grid_slam_figure_files(const GridSlamResult& r, const std::filesystem::path& dir,
                                  bool with_map, std::string_view prefix) {
  require(r.first.has_value(),
          "grid_slam figure: expected the first run kept (keep_first), got none");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  require(!ec, "grid_slam figure: expected a folder '{}' for the figure's files, got: {}",
          dir.string(), ec.message());
  const slam::GridSlamRun& run = *r.first;
  // Written under a temporary name and renamed: a killed run never leaves half a file that the
  // figure script would draw.
  const std::vector<std::string> names = grid_slam_figure_files(r, with_map, prefix);
  write_output_file(dir / names[0], grid_reference_csv(run), "grid_slam figure");
  write_output_file(dir / names[1], grid_track_csv(run), "grid_slam figure");
  if (with_map) write_output_file(dir / names[2], occupied_cells_csv(run.map), "grid_slam figure");
}

nlohmann::json run_grid_slam_reproduce(GridSlamSettings settings,
                                       const std::filesystem::path& figure_dir, bool with_map,
                                       const GridSlamProgress& progress, std::string_view prefix) {
  settings.validate();
  const auto start = std::chrono::steady_clock::now();
  const auto log = cached_carmen_log(settings.data);
  const double read_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const bool figure = !figure_dir.empty();
  settings.keep_first = settings.keep_first || figure;
  const GridSlamResult r = run_grid_slam_experiment(settings, *log, progress);
  nlohmann::json j = to_json(r);
  j["read_seconds"] = read_seconds;
  nlohmann::json files = nlohmann::json::array();
  if (figure) {
    write_grid_slam_figure_files(r, figure_dir, with_map, prefix);
    for (const std::string& name : grid_slam_figure_files(r, with_map, prefix))
      files.push_back(name);
  }
  j["figure_files"] = files;
  return j;
}

}  // namespace implicit::experiments
