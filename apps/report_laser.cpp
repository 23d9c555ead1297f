// The report's section beyond the paper: laser localization on a recorded log (the laser_mcl
// experiment, apps/reproduce_laser.cpp, spec §3.12): tracking against M and global starts.
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "report_parts.hpp"
#include "wilson.hpp"

namespace implicit::app::report::parts {

namespace {

constexpr const char* kExperiment = "laser_mcl";

/// `r[key][field]`: the per-run summaries of laser_mcl's JSON are {mean, se, median} objects.
const json& summary(const json& r, const std::string& key, const std::string& field) {
  return get(get(r, key), field);
}

/// A number scaled (µs to ms), "—" when missing or not finite (null once read back).
std::string scaled(const json& v, double scale, int digits) {
  if (!v.is_number() || !std::isfinite(v.get<double>())) return "—";
  return fmt::format("{:.{}f}", scale * v.get<double>(), digits);
}

std::string rmse_cell(const json& r) {
  const json& mean = summary(r, "position_rmse_m", "mean");
  if (!mean.is_number()) return "—";
  const json& se = summary(r, "position_rmse_m", "se");
  std::string s = scaled(mean, 1.0, 3);
  if (se.is_number() && std::isfinite(se.get<double>()) && r.value("runs", 0) > 1)
    s += " ± " + format_se(se.get<double>());
  return s;
}

/// "rate [low, high]": the global starts that succeeded, with the Wilson 95 % interval.
std::string success_cell(const json& r) {
  const json& k = get(r, "global_successes");
  const json& n = get(r, "runs");
  if (!k.is_number() || !n.is_number() || n.get<double>() < 1) return "—";
  const double count = k.get<double>(), runs = n.get<double>();
  if (count < 0 || count > runs) return "—";
  const auto ci = wilson95(count, runs);
  return fmt::format("{:.0f}/{:.0f} = {:.2f} [{:.2f}, {:.2f}]", count, runs, count / runs, ci[0],
                     ci[1]);
}

/// One row per configuration of the given start ("known": tracking, "global").
Table laser_table(const json& results, const Text& text, const std::string& start) {
  const bool global = start == "global";
  Table t;
  t.header = {text("laser.col.proposal"), text("col.m"), text("col.runs")};
  if (global) {
    t.header.insert(t.header.end(), {text("laser.col.success"), text("laser.col.converge"),
                                     text("laser.col.cpu_update")});
  } else {
    t.header.insert(t.header.end(), {text("laser.col.rmse"), text("laser.col.rmse_median"),
                                     text("laser.col.lost"), text("laser.col.ess"),
                                     text("laser.col.cpu_update"), text("laser.col.cpu_particle")});
  }
  for (const auto& run : experiment_runs(results, kExperiment)) {
    const auto& s = get(run, "settings");
    if (s.value("start", std::string()) != start) continue;
    std::vector<std::string> row = {s.value("proposal", std::string("?")),
                                    std::to_string(s.value("particles", 0))};
    if (!ok(&run)) {
      add_failed_row(t, std::move(row), run);
      continue;
    }
    const json& r = run.at("result");
    row.push_back(std::to_string(r.value("runs", 0)));
    if (global) {
      row.insert(row.end(), {success_cell(r), scaled(get(r, "updates_to_converge_median"), 1, 1),
                             scaled(summary(r, "cpu_us_per_update", "mean"), 1e-3, 2)});
    } else {
      row.insert(row.end(), {rmse_cell(r), scaled(summary(r, "position_rmse_m", "median"), 1, 3),
                             scaled(get(r, "lost_runs"), 1, 0),
                             scaled(summary(r, "ess_fraction", "mean"), 1, 3),
                             scaled(summary(r, "cpu_us_per_update", "mean"), 1e-3, 2),
                             scaled(get(r, "cpu_us_per_update_per_particle"), 1, 2)});
    }
    t.rows.push_back(row);
  }
  return t;
}

/// The dataset as the first result that ran describes it ("—" before any ran).
std::string dataset_line(const json& results, const Text& text) {
  for (const auto& run : experiment_runs(results, kExperiment)) {
    if (!ok(&run)) continue;
    const json& r = run.at("result");
    const json& map = get(r, "map");
    return text.format("laser.dataset", fmt::arg("data", r.value("data", std::string("?"))),
                       fmt::arg("scans", scaled(get(r, "scans_in_log"), 1, 0)),
                       fmt::arg("updates", scaled(get(r, "updates"), 1, 0)),
                       fmt::arg("width", scaled(get(map, "width"), 1, 0)),
                       fmt::arg("height", scaled(get(map, "height"), 1, 0)),
                       fmt::arg("resolution", scaled(get(map, "resolution"), 1, 2)),
                       fmt::arg("load", scaled(get(get(r, "dataset"), "load_seconds"), 1, 2)));
  }
  return text("laser.no_dataset");
}

}  // namespace

void laser_mcl_section(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  doc.heading(2, text("laser.heading"));
  experiment_status(doc, results, text, kExperiment);
  doc.paragraph(text("laser.intro"));
  doc.paragraph(dataset_line(results, text));
  doc.heading(3, text("laser.tracking.heading"));
  doc.paragraph(text("laser.tracking.intro"));
  doc.table(laser_table(results, text, "known"));
  doc.heading(3, text("laser.global.heading"));
  doc.paragraph(text("laser.global.intro"));
  doc.table(laser_table(results, text, "global"));
  figure(doc, results, text, 10, "laser.figure10");
  settings_list(doc, results, text, kExperiment);
}

}  // namespace implicit::app::report::parts
