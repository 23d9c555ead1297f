// The report's section beyond the paper: data assimilation on Lorenz-63 and Lorenz-96 beside
// DAPPER's published rmse.a (the da experiment, apps/reproduce_da.cpp, spec §3.14).
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "report_parts.hpp"

namespace implicit::app::report::parts {

namespace {

constexpr const char* kDaExperiment = "da";

/// The tuning of a row: the settings that differ from the tool's defaults.
std::string tuning(const json& s) {
  std::string t;
  const auto add = [&](const std::string& part) { t += (t.empty() ? "" : ", ") + part; };
  if (get(s, "jitter").is_number() && s["jitter"].get<double>() > 0)
    add(fmt::format("s = {}", s["jitter"].get<double>()));
  if (get(s, "regularisation") == "cov") add("cov");
  if (get(s, "inflation").is_number() && s["inflation"].get<double>() != 1.0)
    add(fmt::format("inflation {}", s["inflation"].get<double>()));
  if (get(s, "resample_threshold").is_number() && s["resample_threshold"].get<double>() != 0.5)
    add(fmt::format("r = {}", s["resample_threshold"].get<double>()));
  if (get(s, "lag").is_number()) add(fmt::format("L = {}", s["lag"].get<int>()));
  if (get(s, "bandwidth").is_number() && s["bandwidth"].get<double>() < 1.0)
    add(fmt::format("kernels h = {}", s["bandwidth"].get<double>()));
  return t.empty() ? "—" : t;
}

Table da_table(const json& results, const Text& text) {
  Table t;
  t.header = {text("da.col.setting"), text("da.col.method"), text("da.col.n"),
              text("da.col.tuning"),  text("col.runs"),      text("da.col.rmse_a"),
              text("da.col.dapper"),  text("da.col.spread"), text("da.col.ess"),
              text("da.col.ms_cycle")};
  for (const auto& run : experiment_runs(results, kDaExperiment)) {
    const auto& s = get(run, "settings");
    std::vector<std::string> row = {s.value("setting", std::string("?")),
                                    s.value("method", std::string("?")),
                                    std::to_string(s.value("members", 0)), tuning(s)};
    if (!ok(&run)) {
      add_failed_row(t, std::move(row), run);
      continue;
    }
    const json& r = run.at("result");
    std::string rmse = number(get(r, "rmse_a_mean"), 3);
    if (get(r, "rmse_a_lo").is_number())
      rmse += " [" + number(get(r, "rmse_a_lo"), 3) + ", " + number(get(r, "rmse_a_hi"), 3) + "]";
    row.insert(row.end(), {std::to_string(r.value("seeds", 0)), rmse,
                           number(get(r, "dapper_rmse_a"), 2), number(get(r, "spread_a"), 3),
                           number(get(r, "mean_ess"), 1), number(get(r, "ms_per_cycle"), 3)});
    t.rows.push_back(row);
  }
  return t;
}

}  // namespace

void da_section(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  table_and_figure_section(doc, results, text, kDaExperiment, "da", da_table(results, text), 12);
}

}  // namespace implicit::app::report::parts
