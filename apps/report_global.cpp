// The report's section beyond the paper: global localization (no initial pose) and kidnapping
// with implicit and standard MCL (apps/exp_mcl_global.cpp, spec §3.10).
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

Table study_table(const json& results, bool kidnap) {
  Table t;
  t.header = {"method",
              "M",
              "runs",
              kidnap ? "recovery rate [95 % CI]" : "success rate [95 % CI]",
              kidnap ? "median time to recover [s]" : "median time to converge [s]",
              "particles (mean)",
              "CPU [ms/step]"};
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
std::string criteria(const json& results) {
  for (const auto& run : experiment_runs(results, "global_localization"))
    if (ok(&run) && run.at("result").contains("criteria"))
      return run.at("result").at("criteria").get<std::string>();
  return "see docs/cli.md";
}

}  // namespace

void global_localization_section(Document& doc, const json& results, const Numbers& /*numbers*/) {
  doc.heading(2, "7. Beyond the paper: global localization and kidnapping");
  experiment_status(doc, results, "global_localization");
  doc.paragraph(fmt::format(
      "Implicit and standard (bootstrap) MCL on the Car Park log without the initial pose "
      "(global start; run r starts r · span / runs seconds into the log) and after a kidnapping "
      "(the filter starts at the known pose, then a stretch of odometry and scans is dropped, so "
      "its pose is wrong without being told). Implicit MCL draws its first and its recovery "
      "particles from the mixture over the minima of −log p(z|x), standard MCL from the uniform "
      "cloud over the map, with AMCL's recovery rule in both (spec §3.10). The implicit filter "
      "uses fewer particles than the standard one since each of its particles costs more; "
      "compare the CPU column. Criteria: {}. The rates' intervals are Wilson 95 % intervals over "
      "the runs; medians are over the runs that converged (recovered). Figure 9 shows the "
      "position error of the first runs of the largest M of each method.",
      criteria(results)));
  doc.heading(3, "Global start");
  doc.table(study_table(results, false));
  doc.heading(3, "Kidnapping");
  doc.table(study_table(results, true));
  figure(doc, results, 9,
         "Position error against time of the first runs of implicit (left) and standard (right) "
         "MCL from a global start (top) and after a kidnapping (bottom), log scale; the dashed "
         "line is the 1 m threshold; dotted lines mark where the clock starts (the global start, "
         "or the "
         "end of the dropped stretch).");
  settings_list(doc, results, "global_localization");
}

}  // namespace implicit::app::report::parts
