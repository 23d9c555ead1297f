// The reproduction report as a whole: its introduction, summary and closing blocks around the
// sections (apps/report_control.cpp, apps/report_filters.cpp), and the side-by-side tables as
// CSV files.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "report_parts.hpp"

namespace implicit::app::report {

using nlohmann::json;
using namespace parts;

// ---- The whole report ------------------------------------------------------------------------

Document build_report(const json& results, const std::filesystem::path& dir) {
  return build_report_with(results, dir, numbers_of(results));
}

namespace parts {

namespace {

// Experiment names are results.json's keys; what the summary says of each is text.
const std::vector<std::string> kSummaryExperiments = {
    "slit",      "arm",       "himmelblau", "mcl", "slam", "proposal_gain", "global_localization",
    "laser_mcl", "grid_slam", "da"};

void introduction(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  doc.set_title(text("report.html_title"));
  doc.heading(1, text("report.heading"));
  doc.paragraph(text.format(
      "intro.generated", fmt::arg("paper", numbers.paper["source"].get<std::string>()),
      fmt::arg("version", results.value("version", "?")),
      fmt::arg("commit", results.value("commit", "?")),
      fmt::arg("started", results.value("started_utc", "?")),
      fmt::arg("threads", results.value("threads", 0)), fmt::arg("seed", results.value("seed", 0)),
      fmt::arg("settings", text(results.value("quick", false) ? "intro.settings_quick"
                                                              : "intro.settings_full")),
      fmt::arg("seconds", results.value("seconds_total", 0.0))));
  doc.paragraph(text("intro.specification"));
  doc.paragraph(agreement_statement(text));

  doc.heading(2, text("summary.heading"));
  Table summary;
  summary.header = {text("summary.col.experiment"), text("summary.col.paper"),
                    text("summary.col.status"), text("summary.col.configurations_ok"),
                    text("summary.col.seconds")};
  for (const auto& name : kSummaryExperiments) {
    const auto& e = get(get(results, "experiments"), name);
    const auto& runs = experiment_runs(results, name);
    int good = 0;
    for (const auto& r : runs) good += r.value("status", std::string()) == "ok";
    summary.rows.push_back({name, text("summary.where." + name), status_of(results, name),
                            fmt::format("{}/{}", good, runs.size()), number(get(e, "seconds"), 1)});
  }
  doc.table(summary);
  Table figures;
  figures.header = {text("figures.col.figure"), text("figures.col.status"),
                    text("figures.col.detail")};
  if (results.contains("figures"))
    for (const auto& [key, f] : results.at("figures").items()) {
      std::string detail;
      if (f.value("status", std::string()) == "ok") {
        for (const auto& file : f.value("files", json::array()))
          detail += (detail.empty() ? "" : ", ") + file.get<std::string>();
      } else {
        detail = f.value("error", std::string());
      }
      figures.rows.push_back({key, f.value("status", std::string("?")), detail});
    }
  // By the figures' numbers: the JSON object sorts its keys as text (figure10 before figure2).
  const auto figure_number = [](const std::string& key) {
    const auto digit = key.find_first_of("0123456789");
    return digit == std::string::npos ? 0 : std::atoi(key.c_str() + digit);
  };
  std::stable_sort(figures.rows.begin(), figures.rows.end(), [&](const auto& a, const auto& b) {
    return figure_number(a[0]) < figure_number(b[0]);
  });
  doc.table(figures);
}

void closing(Document& doc, const json& results, const Text& text) {
  doc.heading(2, text("repeat.heading"));
  doc.code(results.value("command", std::string("implicit reproduce")));
  Table build;
  build.header = {"", text("repeat.col.value")};
  for (const char* key : {"version", "commit", "compiler", "build_type", "cxx_flags", "cpu_model",
                          "hardware_threads", "threads", "seed", "quick", "started_utc"}) {
    if (!results.contains(key)) continue;
    const auto& v = results.at(key);
    build.rows.push_back({key, v.is_string() ? v.get<std::string>() : v.dump()});
  }
  doc.table(build);
  doc.paragraph(text("repeat.files"));

  std::vector<std::string> failures;
  for (const auto& name : kSummaryExperiments)
    for (const auto& run : experiment_runs(results, name))
      if (run.value("status", std::string()) != "ok")
        failures.push_back(fmt::format("{}: {}", run.value("label", name),
                                       run.contains("error") ? run.value("error", std::string())
                                                             : text("status.unknown_error")));
  if (!failures.empty()) {
    doc.heading(2, text("failures.heading"));
    doc.list(failures);
  }
}

}  // namespace

Document build_report_with(const json& results, const std::filesystem::path& dir,
                           const Numbers& numbers) {
  Document doc;
  introduction(doc, results, numbers);
  slit_section(doc, results, numbers);
  arm_section(doc, results, numbers);
  himmelblau_section(doc, results, numbers, dir);
  mcl_section(doc, results, numbers);
  slam_section(doc, results, numbers);
  proposal_gain_section(doc, results, numbers);
  global_localization_section(doc, results, numbers);
  laser_mcl_section(doc, results, numbers);
  grid_slam_section(doc, results, numbers);
  da_section(doc, results, numbers);
  closing(doc, results, numbers.text);
  return doc;
}

}  // namespace parts

// ---- Table CSV files ---------------------------------------------------------------------------

namespace {

std::string csv_value(const json& j) {
  if (j.is_number()) {
    const double v = j.get<double>();
    if (!std::isfinite(v)) return "";
    if (j.is_number_integer()) return std::to_string(j.get<long long>());
    return fmt::format("{}", v);
  }
  if (j.is_string()) return j.get<std::string>();
  if (j.is_boolean()) return j.get<bool>() ? "1" : "0";
  return "";
}

void write_csv(const std::filesystem::path& file, const std::vector<std::string>& columns,
               const std::vector<std::vector<std::string>>& rows) {
  // The tables go into the folder of --out (or of --report-only's results.json, the same flag);
  // under a temporary name, renamed when complete (OutputFile).
  OutputFile out(file);
  for (std::size_t i = 0; i < columns.size(); ++i) out.stream() << (i ? "," : "") << columns[i];
  out.stream() << "\n";
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) out.stream() << (i ? "," : "") << row[i];
    out.stream() << "\n";
  }
  out.commit();
}

// The settings that are names; every other setting and result in a table is a number (or null:
// not computed). results.json may have been edited: a string where a number belongs would
// otherwise be copied into the CSV as if it were a result.
bool table_text_setting(const std::string& key) {
  return key == "mode" || key == "config" || key == "method" || key == "setting";
}

std::string checked_csv_value(const json& value, bool text, const std::string& where,
                              const std::filesystem::path& source) {
  const bool fits =
      value.is_null() || (text ? value.is_string() : value.is_number() || value.is_boolean());
  if (!fits)
    throw ParseError(fmt::format("{}: expected {} at {}, got {} (a {})", source.string(),
                                 text ? "a name (a string)" : "a number or null", where,
                                 printable(value.dump(), 60), value.type_name()));
  return csv_value(value);
}

/// One row per successful configuration: settings columns, then result columns.
std::vector<std::vector<std::string>> rows_of(
    const json& results, const std::string& experiment, const std::filesystem::path& source,
    const std::vector<std::string>& settings_keys, const std::vector<std::string>& result_keys,
    const std::function<std::vector<std::string>(const json& settings)>& extra) {
  std::vector<std::vector<std::string>> rows;
  const auto& runs = experiment_runs(results, experiment);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& run = runs[i];
    if (!ok(&run)) continue;
    const auto& s = run.at("settings");
    const auto& r = run.at("result");
    const std::string where = fmt::format("/experiments/{}/runs/{}", experiment, i);
    std::vector<std::string> row;
    for (const auto& k : settings_keys)
      row.push_back(
          checked_csv_value(get(s, k), table_text_setting(k), where + "/settings/" + k, source));
    for (const auto& k : result_keys)
      row.push_back(checked_csv_value(get(r, k), false, where + "/result/" + k, source));
    for (auto& e : extra(s)) row.push_back(std::move(e));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string paper_lookup(const json& table, const std::string& key, int m) {
  if (!table.contains(key)) return "";
  for (std::size_t i = 0; i < table["samples"].size(); ++i)
    if (table["samples"][i].get<int>() == m) return csv_value(table[key][i]);
  return "";
}

}  // namespace

std::vector<std::string> write_table_csvs(const json& results, const std::filesystem::path& dir,
                                          const std::filesystem::path& source) {
  std::filesystem::create_directories(dir);
  const json paper = numbers_of(results).paper;
  std::vector<std::string> written;
  {
    const std::vector<std::string> s = {"mode", "samples"};
    const std::vector<std::string> r = {"runs",           "error_x_mean",   "error_x_std",
                                        "error_x_median", "error_u_mean",   "error_u_std",
                                        "error_u_median", "crash_fraction", "seconds"};
    std::vector<std::string> columns = s;
    columns.insert(columns.end(), r.begin(), r.end());
    for (const char* c :
         {"paper_error_x_mean", "paper_error_x_std", "paper_error_u_mean", "paper_error_u_std"})
      columns.emplace_back(c);
    const auto& t2 = paper["table2"];
    auto rows = rows_of(results, "slit", source, s, r, [&](const json& settings) {
      const int m = settings.value("samples", 0);
      return std::vector<std::string>{
          paper_lookup(t2, "error_x_mean", m), paper_lookup(t2, "error_x_std", m),
          paper_lookup(t2, "error_u_mean", m), paper_lookup(t2, "error_u_std", m)};
    });
    write_csv(dir / "table2_slit.csv", columns, rows);
    written.emplace_back("table2_slit.csv");
  }
  {
    const std::vector<std::string> s = {"config", "method", "particles"};
    const std::vector<std::string> r = {"runs",
                                        "error_percent_mean",
                                        "error_percent_std",
                                        "error_percent_median",
                                        "rmse_m",
                                        "heading_rmse_rad",
                                        "ess_mean",
                                        "cpu_ms_per_step",
                                        "lost_runs",
                                        "seconds"};
    std::vector<std::string> columns = s;
    columns.insert(columns.end(), r.begin(), r.end());
    columns.emplace_back("paper_error_percent");
    columns.emplace_back("paper_cpu_ms");
    const auto& t5 = paper["table5"];
    auto rows = rows_of(results, "mcl", source, s, r, [&](const json& settings) {
      const std::string method = settings.value("method", std::string());
      const int m = settings.value("particles", 0);
      if (settings.value("config", std::string()) != "A") return std::vector<std::string>{"", ""};
      return std::vector<std::string>{paper_lookup(t5, method + "_error", m),
                                      paper_lookup(t5, method + "_cpu_ms", m)};
    });
    write_csv(dir / "table5_mcl.csv", columns, rows);
    written.emplace_back("table5_mcl.csv");
  }
  {
    const std::vector<std::string> s = {"method", "particles"};
    const std::vector<std::string> r = {
        "datasets",    "error_percent_mean", "error_percent_std", "error_aligned_percent_mean",
        "map_shape_m", "rmse_pose_m",        "rmse_map_m",        "ess_mean",
        "resamplings", "cpu_ms_per_step",    "peak_memory_mb",    "seconds"};
    std::vector<std::string> columns = s;
    columns.insert(columns.end(), r.begin(), r.end());
    columns.emplace_back("paper_error_percent");
    columns.emplace_back("paper_cpu_ms");
    const auto& t6 = paper["table6"];
    auto rows = rows_of(results, "slam", source, s, r, [&](const json& settings) {
      const std::string method = settings.value("method", std::string());
      const int m = settings.value("particles", 0);
      if (method == "ekf")
        return std::vector<std::string>{csv_value(t6["ekf_error"]), csv_value(t6["ekf_cpu_ms"])};
      if (method == "implicit-rb") return std::vector<std::string>{"", ""};
      return std::vector<std::string>{paper_lookup(t6, method + "_error", m),
                                      paper_lookup(t6, method + "_cpu_ms", m)};
    });
    write_csv(dir / "table6_slam.csv", columns, rows);
    written.emplace_back("table6_slam.csv");
  }
  {
    // Data assimilation beside DAPPER (apps/reproduce_da.cpp); figure 12 reads this file.
    const std::vector<std::string> s = {"setting", "method",    "members",
                                        "jitter",  "inflation", "resample_threshold",
                                        "lag",     "bandwidth"};
    const std::vector<std::string> r = {"seeds",    "rmse_a_mean", "rmse_a_lo",    "rmse_a_hi",
                                        "spread_a", "mean_ess",    "ms_per_cycle", "dapper_rmse_a"};
    std::vector<std::string> columns = s;
    columns.insert(columns.end(), r.begin(), r.end());
    auto rows = rows_of(results, "da", source, s, r,
                        [](const json&) { return std::vector<std::string>{}; });
    write_csv(dir / "table_da.csv", columns, rows);
    written.emplace_back("table_da.csv");
  }
  return written;
}

}  // namespace implicit::app::report
