// The pieces of the report's sections: lookups, cells, standard errors, agreement, blocks.
#include "report_parts.hpp"

#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace implicit::app::report::parts {

const json& run_count(const json& result) {
  return get(result, "runs").is_number() ? result["runs"] : get(result, "datasets");
}

// Always the bundled files, never the copies in results.json: those are provenance, and a copy
// edited by hand or written by another version may lack keys the tables read (found by
// fuzz_results_json). The files are validated by read_numbers_file and by the tests.
Numbers numbers_of(const json&) {
  return Numbers{paper_numbers(), reference_numbers(), report_text()};
}

/// The first configuration of an experiment whose settings satisfy `pred` (null if none).
const json* find_run(const json& results, const std::string& experiment, const RunPredicate& pred) {
  for (const auto& run : experiment_runs(results, experiment))
    if (run.contains("settings") && pred(run.at("settings"))) return &run;
  return nullptr;
}

bool ok(const json* run) {
  return run && run->value("status", std::string()) == "ok" && run->contains("result");
}

/// A table cell for one value of a configuration's result.
std::string cell(const json* run, const std::function<std::string(const json&)>& show) {
  if (!run) return "not run";
  if (!ok(run)) return "failed";
  return show(run->at("result"));
}

std::string value_cell(const json* run, const std::string& key, int digits) {
  return cell(run,
              [&](const json& r) { return r.contains(key) ? number(r.at(key), digits) : "–"; });
}

void add_failed_row(Table& t, std::vector<std::string> row, const json& run) {
  row.push_back("—");
  row.push_back(cell(&run, [](const json&) { return ""; }));
  row.resize(t.header.size(), "—");
  t.rows.push_back(std::move(row));
}

std::string int_cell(const json* run, const std::string& key) {
  return cell(run, [&](const json& r) {
    return r.contains(key) && r.at(key).is_number() ? fmt::format("{:.0f}", r.at(key).get<double>())
                                                    : "–";
  });
}

/// ESS/M from a result's `ess_mean`, which experiments report either as a sample count or
/// already divided by M (ESS >= 1 and ESS/M <= 1, so only exactly 1 is ambiguous).
std::string ess_fraction_cell(const json* run, int m, int digits) {
  return cell(run, [&](const json& r) {
    if (!r.contains("ess_mean") || !r["ess_mean"].is_number() || m <= 0) return std::string("–");
    const double e = r["ess_mean"].get<double>();
    const double scale = e > 1.0 ? 1.0 / m : 1.0;  // the sd is in the same unit as the mean
    std::string s = number(e * scale, digits);
    const double se = standard_error(get(r, "ess_std"), run_count(r));
    if (std::isfinite(se)) s += " (SE " + format_se(se * scale) + ")";
    return s;
  });
}

std::string pm(const json& mean, const json& sd, int digits) {
  if (!mean.is_number()) return "–";
  std::string s = number(mean, digits);
  if (sd.is_number()) s += " ± " + number(sd, digits);
  return s;
}

std::string at(const json& array, std::size_t i, int digits) {
  return array.is_array() && i < array.size() ? number(array[i], digits) : "–";
}

const json& get(const json& j, const std::string& key) {
  static const json null;
  return j.is_object() && j.contains(key) ? j.at(key) : null;
}

std::string status_of(const json& results, const std::string& experiment) {
  const auto& e = get(get(results, "experiments"), experiment);
  return e.is_object() ? e.value("status", std::string("not run")) : std::string("not run");
}

/// Figure block: the PNG when the script succeeded, otherwise the reason.
void figure(Document& doc, const json& results, const Text& text, int n,
            const std::string& caption_key) {
  // Looked up also when the figure is missing, so that a missing caption shows in every run.
  const std::string caption = text(caption_key);
  const std::string key = fmt::format("figure{}", n);
  const auto& f = get(get(results, "figures"), key);
  const std::string status = f.is_object() ? f.value("status", std::string("not run")) : "not run";
  if (status == "ok") {
    doc.image(key + ".png",
              text.format("figure.caption", fmt::arg("n", n), fmt::arg("caption", caption)));
  } else {
    const std::string reason = f.is_object() && f.contains("error")
                                   ? f.value("error", std::string())
                                   : text("figure.not_produced");
    doc.paragraph(text.format(status == "skipped" ? "figure.skipped" : "figure.missing",
                              fmt::arg("n", n), fmt::arg("reason", reason)));
  }
}

void settings_list(Document& doc, const json& results, const Text& text,
                   const std::string& experiment) {
  const auto& s = get(get(results, "settings"), experiment);
  if (!s.is_object()) return;
  std::vector<std::string> items;
  for (const auto& [k, v] : s.items()) items.push_back(fmt::format("`{}`: {}", k, v.dump()));
  doc.paragraph(text("settings.intro"));
  doc.list(items);
}

namespace {

std::string failures_note(const json& results, const Text& text, const std::string& experiment) {
  std::string note;
  for (const auto& run : experiment_runs(results, experiment))
    if (run.value("status", std::string()) != "ok") {
      note = text.format("status.run_failed", fmt::arg("label", run.value("label", experiment)),
                         fmt::arg("error", run.contains("error") ? run.value("error", std::string())
                                                                 : text("status.unknown_error")));
      break;
    }
  return note;
}

}  // namespace

void table_and_figure_section(Document& doc, const json& results, const Text& text,
                              const std::string& experiment, const std::string& prefix,
                              const Table& table, int figure_number) {
  doc.heading(2, text(prefix + ".heading"));
  experiment_status(doc, results, text, experiment);
  doc.paragraph(text(prefix + ".intro"));
  doc.table(table);
  doc.paragraph(text(prefix + ".reading"));
  figure(doc, results, text, figure_number, fmt::format("{}.figure{}", prefix, figure_number));
  settings_list(doc, results, text, experiment);
}

void experiment_status(Document& doc, const json& results, const Text& text,
                       const std::string& experiment) {
  const std::string s = status_of(results, experiment);
  if (s == "ok") return;
  const std::string f = failures_note(results, text, experiment);
  doc.paragraph(f.empty() ? text.format("status.line", fmt::arg("status", s))
                          : text.format("status.line_with_failure", fmt::arg("status", s),
                                        fmt::arg("failure", f)));
}

std::string mean_se_cell(const json* run, const std::string& key, const std::string& sd_key,
                         int digits) {
  return cell(run, [&](const json& r) {
    if (!r.contains(key)) return std::string("–");
    std::string s = number(r.at(key), digits);
    const double se = standard_error(get(r, sd_key), run_count(r));
    if (std::isfinite(se)) s += " (SE " + format_se(se) + ")";
    return s;
  });
}

Estimate ours_estimate(const json* run, const std::string& prefix) {
  Estimate e;
  if (!ok(run)) return e;
  const json& r = run->at("result");
  const json& mean = get(r, prefix + "_mean");
  if (mean.is_number()) e.mean = mean.get<double>();
  e.se = standard_error(get(r, prefix + "_std"), run_count(r));
  return e;
}

Estimate reference_estimate(const json& mean, const json& sd, const json& n) {
  Estimate e;
  if (mean.is_number()) e.mean = mean.get<double>();
  e.se = standard_error(sd, n);
  return e;
}

Estimate fraction_estimate(const json& p, const json& n) {
  Estimate e;
  if (!p.is_number() || !n.is_number() || n.get<double>() < 1.0) return e;
  e.mean = p.get<double>();
  e.se = std::sqrt(e.mean * (1.0 - e.mean) / n.get<double>());
  return e;
}

std::string agreement_statement(const Text& text) {
  return text.format("intro.agreement", fmt::arg("sigmas", kAgreementSigmas));
}

}  // namespace implicit::app::report::parts
