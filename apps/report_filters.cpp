// The report's sections on filtering: Monte Carlo localization and SLAM (paper §4). The paper's
// numbers cannot be matched there (its noise setting is unknown, its SLAM data are not
// available), so each section shows the comparison with the independent reference first, with
// its agreement column, and the paper's tables after it.
#include <algorithm>

#include <fmt/format.h>

#include "report_parts.hpp"

namespace implicit::app::report::parts {

namespace {

/// M of the paper's table plus every M we ran (`keep` selects the configurations that count).
std::vector<int> particle_counts(const json& results, const std::string& experiment,
                                 const json& paper, const RunPredicate& keep) {
  std::vector<int> ms;
  for (const auto& m : paper["samples"]) ms.push_back(m.get<int>());
  for (const auto& run : experiment_runs(results, experiment)) {
    const auto& s = get(run, "settings");
    if (!keep(s)) continue;
    const int m = s.value("particles", 0);
    if (std::find(ms.begin(), ms.end(), m) == ms.end()) ms.push_back(m);
  }
  std::sort(ms.begin(), ms.end());
  return ms;
}

/// Index of M in the paper's "samples" (its size when absent).
std::size_t paper_index(const json& paper, int m) {
  std::size_t pi = paper["samples"].size();
  for (std::size_t i = 0; i < paper["samples"].size(); ++i)
    if (paper["samples"][i].get<int>() == m) pi = i;
  return pi;
}

std::string err_cell(const json* run) {
  return cell(run, [](const json& r) { return spread(r, "error_percent", 2); });
}

// ---- MCL ----------------------------------------------------------------------------------------

const json* find_mcl(const json& results, const std::string& method, int m,
                     const std::string& config) {
  return find_run(results, "mcl", [&](const json& s) {
    return s.value("method", std::string()) == method && s.value("particles", 0) == m &&
           s.value("config", std::string()) == config;
  });
}

Table mcl_reference_table(const json& results, const json& ref, const Text& text) {
  Table r;
  r.caption = text.format("mcl.reference.caption", fmt::arg("seeds", ref["runs"].get<int>()));
  r.header = {text("mcl.col.config"),
              text("col.m"),
              text("col.method"),
              text("col.reference_err"),
              text("col.ours_err"),
              text("col.agree"),
              text("mcl.reference.col.reference_rmse"),
              text("mcl.reference.col.ours_rmse"),
              text("mcl.reference.col.reference_lost"),
              text("mcl.reference.col.ours_lost"),
              text("col.runs")};
  for (const auto& row : ref["rows"]) {
    const std::string config = row["config"];
    const int m = row["particles"];
    for (const std::string method : {"implicit", "standard"}) {
      const json& c = row[method];
      std::string rs = pm(c["error_percent_mean"], c["error_percent_std"], 2);
      if (c["error_percent_median"].is_number())
        rs += " (med " + number(c["error_percent_median"], 2) + ")";
      const json* run = find_mcl(results, method, m, config);
      const Estimate reference =
          reference_estimate(c["error_percent_mean"], c["error_percent_std"], ref["runs"]);
      r.rows.push_back({config, std::to_string(m), method, rs, err_cell(run),
                        agreement(ours_estimate(run, "error_percent"), reference),
                        number(c["rmse_m"], 3), mean_se_cell(run, "rmse_m", "rmse_m_std", 3),
                        number(c["lost_runs"], 0), int_cell(run, "lost_runs"),
                        int_cell(run, "runs")});
    }
  }
  return r;
}

Table mcl_paper_table(const json& results, const json& paper, const std::vector<int>& ms,
                      const std::string& method, const Text& text) {
  Table t;
  t.caption = text("mcl.paper.caption." + method);
  t.header = {text("col.m"),
              text("col.paper_err"),
              text("col.ours_err"),
              text("mcl.paper.col.rmse"),
              text("mcl.paper.col.lost"),
              text("col.ess"),
              text("col.paper_cpu"),
              text("col.ours_cpu"),
              text("col.runs")};
  for (const int m : ms) {
    const std::size_t pi = paper_index(paper, m);
    const json* run = find_mcl(results, method, m, "A");
    const bool paper_has = pi < paper["samples"].size() && paper[method + "_error"][pi].is_number();
    if (!run && !paper_has) continue;
    t.rows.push_back({std::to_string(m), at(paper[method + "_error"], pi, 2), err_cell(run),
                      mean_se_cell(run, "rmse_m", "rmse_m_std", 2), int_cell(run, "lost_runs"),
                      ess_fraction_cell(run, m, 2), at(paper[method + "_cpu_ms"], pi, 2),
                      mean_se_cell(run, "cpu_ms_per_step", "cpu_ms_per_step_std", 4),
                      int_cell(run, "runs")});
  }
  return t;
}

// ---- SLAM ---------------------------------------------------------------------------------------

const json* find_slam(const json& results, const std::string& method, int m) {
  return find_run(results, "slam", [&](const json& s) {
    return s.value("method", std::string()) == method &&
           (method == "ekf" || s.value("particles", 0) == m);
  });
}

Table slam_reference_table(const json& results, const json& ref, const Text& text) {
  Table r;
  const int m = ref["particles"].get<int>();
  r.caption = text.format("slam.reference.caption", fmt::arg("m", m),
                          fmt::arg("datasets", ref["datasets"].get<int>()));
  r.header = {text("col.method"),
              text("col.reference_err"),
              text("col.ours_err"),
              text("col.agree"),
              text("slam.reference.col.pose_rmse"),
              text("slam.reference.col.landmark_rmse"),
              text("col.map_shape"),
              text("col.ess"),
              text("col.resamplings")};
  for (const auto& row : ref["rows"]) {
    const std::string method = row["method"];
    const bool ekf = method == "ekf";
    const json* run = find_slam(results, method, m);
    auto both = [](const std::string& reference, const std::string& ours) {
      return reference + " / " + ours;
    };
    const Estimate reference =
        reference_estimate(row["error_percent_mean"], row["error_percent_std"], ref["datasets"]);
    r.rows.push_back(
        {method, pm(row["error_percent_mean"], row["error_percent_std"], 2), err_cell(run),
         agreement(ours_estimate(run, "error_percent"), reference),
         both(number(row["rmse_pose_m"], 2),
              mean_se_cell(run, "rmse_pose_m", "rmse_pose_m_std", 2)),
         both(number(row["rmse_map_m"], 2), mean_se_cell(run, "rmse_map_m", "rmse_map_m_std", 2)),
         both(number(row["map_shape_m"], 3),
              mean_se_cell(run, "map_shape_m", "map_shape_m_std", 3)),
         both(number(row["ess_mean"], 3), ekf ? "–" : ess_fraction_cell(run, m, 3)),
         both(number(row["resamplings"], 0),
              ekf ? "–" : mean_se_cell(run, "resamplings", "resamplings_std", 0))});
  }
  return r;
}

Table slam_paper_table(const json& results, const json& paper, const std::vector<int>& ms,
                       const std::string& method, const Text& text) {
  Table t;
  t.caption = text.format("slam.paper.caption", fmt::arg("method", text("slam.method." + method)));
  t.header = {text("col.m"),           text("col.paper_err"),
              text("col.ours_err"),    text("slam.paper.col.ours_aligned_err"),
              text("col.map_shape"),   text("col.ess"),
              text("col.resamplings"), text("col.paper_cpu"),
              text("col.ours_cpu"),    text("slam.paper.col.datasets")};
  const std::string pkey = method == "implicit-rb" ? "" : method;
  for (const int m : ms) {
    const std::size_t pi = paper_index(paper, m);
    const bool paper_has =
        !pkey.empty() && pi < paper["samples"].size() && paper[pkey + "_error"][pi].is_number();
    const json* run = find_slam(results, method, m);
    if (!run && !paper_has) continue;
    t.rows.push_back(
        {std::to_string(m), paper_has ? at(paper[pkey + "_error"], pi, 2) : "–", err_cell(run),
         mean_se_cell(run, "error_aligned_percent_mean", "error_aligned_percent_std", 2),
         mean_se_cell(run, "map_shape_m", "map_shape_m_std", 3), ess_fraction_cell(run, m, 3),
         mean_se_cell(run, "resamplings", "resamplings_std", 0),
         paper_has ? at(paper[pkey + "_cpu_ms"], pi, 2) : "–",
         value_cell(run, "cpu_ms_per_step", 4), int_cell(run, "datasets")});
  }
  return t;
}

Table slam_ekf_table(const json& results, const json& paper, const json& ref, const Text& text) {
  const json* ekf = find_slam(results, "ekf", 0);
  const json& row = ref["rows"][0];
  Table e;
  e.caption = text("slam.ekf.caption");
  e.header = {"", text("col.paper"), text("col.reference"), text("col.ours"),
              text("slam.ekf.col.agree_reference")};
  e.rows.push_back({text("slam.ekf.row.err"), number(paper["ekf_error"], 2),
                    pm(row["error_percent_mean"], row["error_percent_std"], 2), err_cell(ekf),
                    agreement(ours_estimate(ekf, "error_percent"),
                              reference_estimate(row["error_percent_mean"],
                                                 row["error_percent_std"], ref["datasets"]))});
  e.rows.push_back({text("col.map_shape"), "–", number(row["map_shape_m"], 3),
                    mean_se_cell(ekf, "map_shape_m", "map_shape_m_std", 3), "–"});
  e.rows.push_back({text("slam.ekf.row.cpu"), number(paper["ekf_cpu_ms"], 2), "–",
                    value_cell(ekf, "cpu_ms_per_step", 4), "–"});
  return e;
}

}  // namespace

void mcl_section(Document& doc, const json& results, const Numbers& numbers) {
  const json& paper = numbers.paper["table5"];
  const json& ref = numbers.reference["table5"];
  const Text& text = numbers.text;
  doc.heading(2, text("mcl.heading"));
  experiment_status(doc, results, text, "mcl");
  doc.paragraph(text("mcl.intro"));
  doc.paragraph(text("mcl.read_reference_first"));
  doc.table(mcl_reference_table(results, ref, text));
  doc.paragraph(text("mcl.reference_source"));
  const auto& converged = ref["converged_error_percent_A"];
  doc.paragraph(
      text.format("mcl.converged", fmt::arg("a_low", number(converged[0], 2)),
                  fmt::arg("a_high", number(converged[1], 2)),
                  fmt::arg("b", number(ref["converged_error_percent_B"], 2)),
                  fmt::arg("dead_reckoning", number(ref["dead_reckoning_error_percent"], 1))));
  const auto ms = particle_counts(
      results, "mcl", paper, [](const json& s) { return s.value("config", std::string()) == "A"; });
  for (const std::string method : {"implicit", "standard"})
    doc.table(mcl_paper_table(results, paper, ms, method, text));
  figure(doc, results, text, 6, "mcl.figure6");
  doc.heading(3, text("differences.heading"));
  doc.list(text.items("mcl.differences"));
  settings_list(doc, results, text, "mcl");
}

void slam_section(Document& doc, const json& results, const Numbers& numbers) {
  const json& paper = numbers.paper["table6"];
  const json& ref = numbers.reference["table6"];
  const Text& text = numbers.text;
  doc.heading(2, text("slam.heading"));
  experiment_status(doc, results, text, "slam");
  doc.paragraph(text("slam.intro"));
  doc.table(slam_reference_table(results, ref, text));
  doc.paragraph(text("slam.reference_source"));
  const auto ms = particle_counts(results, "slam", paper, [](const json& s) {
    return s.value("method", std::string()) != "ekf";
  });
  for (const std::string method : {"fastslam1", "fastslam2", "implicit", "implicit-rb"})
    doc.table(slam_paper_table(results, paper, ms, method, text));
  doc.table(slam_ekf_table(results, paper, ref, text));
  figure(doc, results, text, 7, "slam.figure7");
  doc.heading(3, text("differences.heading"));
  doc.list(text.items("slam.differences"));
  settings_list(doc, results, text, "slam");
}

}  // namespace implicit::app::report::parts
