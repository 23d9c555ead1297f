// The report's section beyond the paper: grid SLAM on the bundled laser logs (the grid_slam
// experiment, apps/reproduce_grid_slam.cpp, spec §3.13): the three proposals on one filter.
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "report_parts.hpp"

namespace implicit::app::report::parts {

namespace {

constexpr const char* kGridSlamExperiment = "grid_slam";

/// A number with `digits` decimals, "—" when missing or not finite (null once read back).
std::string grid_number(const json& v, int digits) {
  if (!v.is_number() || !std::isfinite(v.get<double>())) return "—";
  return fmt::format("{:.{}f}", v.get<double>(), digits);
}

/// "mean ± se" of a {mean, se} object (the ± only over several runs).
std::string grid_mean_se(const json& r, const std::string& key, int digits) {
  const json& m = get(r, key);
  std::string s = grid_number(get(m, "mean"), digits);
  const json& se = get(m, "se");
  if (s != "—" && se.is_number() && std::isfinite(se.get<double>()) && r.value("datasets", 0) > 1)
    s += " ± " + format_se(se.get<double>());
  return s;
}

Table grid_slam_table(const json& results, const Text& text) {
  Table t;
  t.header = {text("grid.col.data"),     text("grid.col.proposal"), text("col.m"),
              text("col.runs"),          text("grid.col.scans"),    text("grid.col.translation"),
              text("grid.col.rotation"), text("grid.col.odometry"), text("grid.col.ate"),
              text("grid.col.map_f1"),   text("grid.col.ess"),      text("grid.col.cpu_scan"),
              text("grid.col.real_time")};
  for (const auto& run : experiment_runs(results, kGridSlamExperiment)) {
    const auto& s = get(run, "settings");
    std::vector<std::string> row = {s.value("data", std::string("?")),
                                    s.value("proposal", std::string("?")),
                                    std::to_string(s.value("particles", 0))};
    if (!ok(&run)) {
      add_failed_row(t, std::move(row), run);
      continue;
    }
    const json& r = run.at("result");
    const std::string odometry = grid_number(get(r, "odometry_relation_translation_m"), 4) +
                                 " m, " + grid_number(get(r, "odometry_relation_rotation_deg"), 2) +
                                 "°";
    row.insert(
        row.end(),
        {std::to_string(r.value("datasets", 0)), grid_number(get(r, "scans_processed"), 0),
         grid_mean_se(r, "relation_translation_m", 4), grid_mean_se(r, "relation_rotation_deg", 2),
         odometry, grid_mean_se(r, "ate_m", 3),
         grid_mean_se(r, "map_f1", 3) + " (" + grid_number(get(r, "odometry_map_f1"), 3) + ")",
         grid_number(get(r, "ess_fraction"), 2), grid_mean_se(r, "cpu_ms_per_scan", 1),
         grid_number(get(r, "real_time_factor"), 0)});
    t.rows.push_back(row);
  }
  return t;
}

}  // namespace

void grid_slam_section(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  table_and_figure_section(doc, results, text, kGridSlamExperiment, "grid",
                           grid_slam_table(results, text), 11);
}

}  // namespace implicit::app::report::parts
