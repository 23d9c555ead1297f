// The report's section beyond the paper: global localization (no initial pose) and kidnapping
// with implicit and standard MCL (experiments/landmark_mcl_global.cpp, spec §3.11).
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "report_parts.hpp"
#include "wilson.hpp"

namespace implicit::app::report::parts {

namespace {

/// "rate [low, high]" of a success (recovery) rate over `runs` runs with its Wilson 95 % interval.
std::string rate_cell(const json& r, const std::string& key) {
  const double n = r.value("runs", 0.0);
  if (!r.contains(key) || n <= 0) return "—";
  const double rate = r.at(key).get<double>();
  const auto ci = wilson95(std::round(rate * n), n);
  return fmt::format("{:.2f} [{:.2f}, {:.2f}]", rate, ci[0], ci[1]);
}

std::string number_cell(const json& r, const std::string& key, int digits) {
  const auto& v = get(r, key);
  // A median over no converged run is NaN (null once results.json is read back).
  if (!v.is_number() || !std::isfinite(v.get<double>())) return "—";
  return fmt::format("{:.{}f}", v.get<double>(), digits);
}

Table study_table(const json& results, const Text& text, bool kidnap) {
  Table t;
  t.header = {text("col.method"),
              text("col.m"),
              text("col.runs"),
              text(kidnap ? "global.col.recovery_rate" : "global.col.success_rate"),
              text(kidnap ? "global.col.time_to_recover" : "global.col.time_to_converge"),
              text("global.col.particles"),
              text("global.col.cpu")};
  for (const auto& run : experiment_runs(results, "global_localization")) {
    const auto& s = get(run, "settings");
    if ((s.value("kidnap_at", -1.0) >= 0) != kidnap) continue;
    const std::string method = s.value("method", std::string("?"));
    const std::string m = std::to_string(s.value("particles", 0));
    if (!ok(&run)) {
      t.rows.push_back({method, m, "—", cell(&run, [](const json&) { return ""; }), "—", "—", "—"});
      continue;
    }
    const json& r = run.at("result");
    t.rows.push_back(
        {method, m, std::to_string(r.value("runs", 0)),
         rate_cell(r, kidnap ? "kidnap_recovery_rate" : "global_success_rate"),
         number_cell(r, kidnap ? "recovery_time_s_median" : "time_to_converge_s_median", 1),
         number_cell(r, "particles_mean", 0), number_cell(r, "cpu_ms_per_step", 3)});
  }
  return t;
}

/// The success criteria as the runs state them (the first result that has them).
std::string criteria(const json& results, const Text& text) {
  for (const auto& run : experiment_runs(results, "global_localization"))
    if (ok(&run) && run.at("result").contains("criteria"))
      return run.at("result").at("criteria").get<std::string>();
  return text("global.criteria_elsewhere");
}

}  // namespace

void global_localization_section(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  doc.heading(2, text("global.heading"));
  experiment_status(doc, results, text, "global_localization");
  doc.paragraph(text.format("global.intro", fmt::arg("criteria", criteria(results, text))));
  doc.heading(3, text("global.start.heading"));
  doc.table(study_table(results, text, false));
  doc.heading(3, text("global.kidnap.heading"));
  doc.table(study_table(results, text, true));
  figure(doc, results, text, 9, "global.figure9");
  settings_list(doc, results, text, "global_localization");
}

}  // namespace implicit::app::report::parts
