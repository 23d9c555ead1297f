// The report's sections on path integral control: the double slit, the robot arm and the
// Himmelblau function (paper §3).
#include <cstdlib>

#include <fmt/format.h>

#include "report_parts.hpp"

namespace implicit::app::report::parts {

namespace {

/// Table 2 with the reference's two estimators and an agreement column for each.
Table slit_table(const json& results, const json& paper, const json& ref, const Text& text) {
  Table t;
  t.caption = text("slit.table.caption");
  t.header = {text("col.m"),
              text("col.quantity"),
              text("col.paper"),
              text("slit.table.col.reference_paper"),
              text("slit.table.col.ours_paper"),
              text("col.agree"),
              text("slit.table.col.reference_corrected"),
              text("slit.table.col.ours_corrected"),
              text("col.agree")};
  const auto& samples = paper["samples"];
  const json& ref_runs = ref["runs"];
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const int m = samples[i].get<int>();
    auto run = [&](const std::string& mode) {
      return find_run(results, "slit", [&](const json& s) {
        return s.value("samples", 0) == m && s.value("mode", std::string()) == mode;
      });
    };
    const json* rp = run("paper");
    const json* rc = run("corrected");
    for (const std::string qs : {"error_x", "error_u"}) {
      auto ref_cell = [&](const char* mode) {
        const json& r = ref[mode];
        std::string s = pm(r[qs + "_mean"][i], r[qs + "_std"][i], 2);
        if (r.contains(qs + "_median") && r[qs + "_median"][i].is_number())
          s += " (med " + number(r[qs + "_median"][i], 1) + ")";
        return s;
      };
      auto agree = [&](const json* ours, const char* mode) {
        const json& r = ref[mode];
        return agreement(ours_estimate(ours, qs),
                         reference_estimate(r[qs + "_mean"][i], r[qs + "_std"][i], ref_runs));
      };
      auto ours = [&](const json* r) {
        return cell(r, [&](const json& x) { return spread(x, qs, 2); });
      };
      t.rows.push_back({std::to_string(m), qs == "error_x" ? "e_x %" : "e_u %",
                        pm(paper[qs + "_mean"][i], paper[qs + "_std"][i], 2), ref_cell("paper"),
                        ours(rp), agree(rp, "paper"), ref_cell("corrected"), ours(rc),
                        agree(rc, "corrected")});
    }
    // A crash fraction is a fraction of runs: binomial SE on both sides.
    auto crash = [&](const json* r, const char* mode) {
      if (!ok(r)) return std::string("–");
      const json& x = r->at("result");
      return agreement(fraction_estimate(get(x, "crash_fraction"), get(x, "runs")),
                       fraction_estimate(ref[mode]["crash_fraction"], ref_runs));
    };
    t.rows.push_back({std::to_string(m), text("slit.table.crash_fraction"), "–",
                      fmt::format("≈ {:.2f}", ref["paper"]["crash_fraction"].get<double>()),
                      value_cell(rp, "crash_fraction", 3), crash(rp, "paper"),
                      fmt::format("≈ {:.2f}", ref["corrected"]["crash_fraction"].get<double>()),
                      value_cell(rc, "crash_fraction", 3), crash(rc, "corrected")});
  }
  return t;
}

}  // namespace

void slit_section(Document& doc, const json& results, const Numbers& numbers) {
  const json& paper = numbers.paper["table2"];
  const json& ref = numbers.reference["table2"];
  const Text& text = numbers.text;
  doc.heading(2, text("slit.heading"));
  experiment_status(doc, results, text, "slit");
  doc.paragraph(text("slit.intro"));
  doc.table(slit_table(results, paper, ref, text));
  const json* any = find_run(results, "slit", [](const json&) { return true; });
  std::string exact_crash = "–";
  if (ok(any)) {
    const auto& r = any->at("result");
    exact_crash = number(get(r, "exact_crash_fraction"), 3);
    doc.paragraph(text.format("slit.naive_mc",
                              fmt::arg("passed", number(get(r, "naive_mc_passed"), 0)),
                              fmt::arg("samples", number(get(r, "naive_mc_samples"), 0))));
  }
  doc.paragraph(text.format("slit.runs_per_cell", fmt::arg("runs", paper["runs"].get<int>()),
                            fmt::arg("reference", ref["exact_crash_fraction"].get<double>()),
                            fmt::arg("ours", exact_crash)));
  figure(doc, results, text, 1, "slit.figure1");
  figure(doc, results, text, 2, "slit.figure2");
  doc.heading(3, text("differences.heading"));
  doc.list(text.items("slit.differences"));
  settings_list(doc, results, text, "slit");
}

void arm_section(Document& doc, const json& results, const Numbers& numbers) {
  const json& ref = numbers.reference["arm"];
  const Text& text = numbers.text;
  doc.heading(2, text("arm.heading"));
  experiment_status(doc, results, text, "arm");
  const json* run = find_run(results, "arm", [](const json&) { return true; });
  Table t;
  t.caption = text("arm.table.caption");
  t.header = {text("col.quantity"), text("col.paper"), text("col.reference"), text("col.ours"),
              text("col.agree")};
  t.rows.push_back({text("arm.row.lqr"), text("arm.row.lqr.paper"), text("arm.row.lqr.reference"),
                    cell(run, [](const json& r) {
                      return r.contains("lqr_max_abs_diff")
                                 ? fmt::format("{:.2e}", r["lqr_max_abs_diff"].get<double>())
                                 : "–";
                    })});
  t.rows.push_back({text("arm.row.error_exact"), text("arm.paper_closely_follow"),
                    number(ref["final_angle_error_exact_rad"], 4),
                    value_cell(run, "final_angle_error_exact_rad", 4)});
  t.rows.push_back({text("arm.row.error_wrong_model"), text("arm.paper_closely_follow"),
                    number(ref["final_angle_error_wrong_model_rad"], 4),
                    value_cell(run, "final_angle_error_wrong_model_rad", 4)});
  auto pair = [](const json& r, const char* key, int digits) {
    if (!r.contains(key) || !r[key].is_array() || r[key].size() < 2) return std::string("–");
    return fmt::format("({}, {})", number(r[key][0], digits), number(r[key][1], digits));
  };
  t.rows.push_back({text("arm.row.theta_exact"), "–", pair(ref, "theta_final_exact", 6),
                    cell(run, [&](const json& r) { return pair(r, "final_state_exact", 6); })});
  t.rows.push_back(
      {text("arm.row.theta_wrong_model"), "–", pair(ref, "theta_final_wrong_model", 6),
       cell(run, [&](const json& r) { return pair(r, "final_state_wrong_model", 6); })});
  t.rows.push_back({text("arm.row.torque_exact"), "–", pair(ref, "initial_torque_exact", 6),
                    cell(run, [&](const json& r) { return pair(r, "initial_torque_exact", 6); })});
  t.rows.push_back(
      {text("arm.row.torque_wrong_model"), "–", pair(ref, "initial_torque_wrong_model", 6),
       cell(run, [&](const json& r) { return pair(r, "initial_torque_wrong_model", 6); })});
  // One noise-free run on both sides: no standard error, so the test cannot be computed and
  // the digits are compared instead.
  for (auto& row : t.rows) row.push_back("–");
  doc.table(t);
  doc.paragraph(text.format("arm.reference",
                            fmt::arg("exact1", number(ref["theta_final_exact"][0], 5)),
                            fmt::arg("exact2", number(ref["theta_final_exact"][1], 5)),
                            fmt::arg("wrong1", number(ref["theta_final_wrong_model"][0], 5)),
                            fmt::arg("wrong2", number(ref["theta_final_wrong_model"][1], 5)),
                            fmt::arg("target1", number(ref["theta_target"][0], 0)),
                            fmt::arg("target2", number(ref["theta_target"][1], 1))));
  figure(doc, results, text, 4, "arm.figure4");
  doc.heading(3, text("differences.heading"));
  doc.list(text.items("arm.differences"));
  settings_list(doc, results, text, "arm");
}

namespace {

/// Our mean `key` of a Himmelblau run and its standard error `key_se`.
Estimate himmelblau_estimate(const json* run, const std::string& key) {
  Estimate e;
  if (!ok(run)) return e;
  const json& r = run->at("result");
  if (get(r, key).is_number()) e.mean = r[key].get<double>();
  if (get(r, key + "_se").is_number()) e.se = r[key + "_se"].get<double>();
  return e;
}

/// The closed form `key` of a run's "expected" (exact: SE 0).
Estimate closed_form(const json* run, const std::string& key) {
  Estimate e;
  if (!ok(run)) return e;
  const json& x = get(run->at("result"), "expected");
  if (get(x, key).is_number()) e = {x[key].get<double>(), 0.0};
  return e;
}

/// Newton and the controlled runs against the paper, the reference and the closed form.
Table himmelblau_table(const json* run, const json* many, const json& paper, const json& ref,
                       const Text& text) {
  Table t;
  t.caption = text("himmelblau.table.caption");
  // The closed loop is a discrete Brownian bridge around the basin's minimum, so the expected
  // cost has a closed form (himmelblau.hpp); runs carry it as "expected".
  t.header = {text("col.quantity"),
              text("col.paper"),
              text("col.reference"),
              text("himmelblau.table.col.closed_form"),
              text("col.ours"),
              text("himmelblau.table.col.agree_reference"),
              text("himmelblau.table.col.agree_closed_form")};
  auto expected = [&](const json* r, const char* key, int digits) {
    return cell(r, [&](const json& x) {
      const json& e = get(x, "expected");
      return e.is_object() && e.contains(key) ? number(e[key], digits) : std::string("–");
    });
  };
  auto mean_se = [](const json* r, const std::string& key, int digits) {
    return cell(r, [&](const json& x) {
      std::string c = number(get(x, key), digits);
      if (get(x, key + "_se").is_number())
        c += " (SE " + format_se(x[key + "_se"].get<double>()) + ")";
      return c;
    });
  };
  // The reference stores standard errors: `mean_cost_sd` is that of its 400-run mean cost,
  // `mean_f_x19_se` that of its mean f(x_19) (data/report/README.md).
  auto ref_estimate = [&](const char* mean, const char* se) {
    Estimate e;
    if (get(ref, mean).is_number()) e.mean = ref[mean].get<double>();
    if (get(ref, se).is_number()) e.se = ref[se].get<double>();
    return e;
  };
  const Estimate ref_cost = ref_estimate("mean_cost", "mean_cost_sd");
  const Estimate ref_f_x19 = ref_estimate("mean_f_x19", "mean_f_x19_se");
  auto cost_row = [&](const json* r, std::string label, std::string paper_cell) {
    return std::vector<std::string>{
        std::move(label),
        std::move(paper_cell),
        text.format("himmelblau.row.cost.reference",
                    fmt::arg("value", pm(ref["mean_cost"], ref["mean_cost_sd"], 3))),
        expected(r, "cost", 4),
        mean_se(r, "mean_cost", 3),
        agreement(himmelblau_estimate(r, "mean_cost"), ref_cost),
        agreement(himmelblau_estimate(r, "mean_cost"), closed_form(r, "cost"))};
  };
  t.rows.push_back({text("himmelblau.row.newton"), number(paper["newton_final_f"], 2),
                    text.format("himmelblau.row.newton.reference",
                                fmt::arg("value", number(ref["newton_final_f"], 4))),
                    "–", value_cell(run, "newton_final_f", 4), "–", "–"});
  t.rows.push_back({text("himmelblau.row.runs"), std::to_string(paper["runs_total"].get<int>()),
                    number(ref["mean_cost_runs"], 0), "–", int_cell(run, "runs"), "–", "–"});
  t.rows.push_back({text("himmelblau.row.below_10"),
                    text.format("himmelblau.row.below_10.paper",
                                fmt::arg("value", number(paper["runs_below_10"], 0))),
                    text("himmelblau.row.below_10.reference"), "–", int_cell(run, "runs_below_10"),
                    "–", "–"});
  t.rows.push_back(
      cost_row(run, text("himmelblau.row.cost"), "≈ " + number(paper["mean_cost"], 2)));
  t.rows.push_back({text("himmelblau.row.f_x19"), text("himmelblau.row.f_x19.paper"),
                    text.format("himmelblau.row.f_x19.reference",
                                fmt::arg("value", pm(ref["mean_f_x19"], ref["mean_f_x19_se"], 2))),
                    expected(run, "f_before_last_step", 4),
                    mean_se(run, "mean_f_before_last_step", 3),
                    agreement(himmelblau_estimate(run, "mean_f_before_last_step"), ref_f_x19),
                    agreement(himmelblau_estimate(run, "mean_f_before_last_step"),
                              closed_form(run, "f_before_last_step"))});
  t.rows.push_back(
      {text("himmelblau.row.final_f"), "–", text("himmelblau.row.final_f.reference"),
       expected(run, "final_f", 4), mean_se(run, "mean_final_f", 3), "–",
       agreement(himmelblau_estimate(run, "mean_final_f"), closed_form(run, "final_f"))});
  auto point = [](const json& r, const char* key) {
    if (!r.contains(key) || !r[key].is_array() || r[key].size() != 2) return std::string("–");
    return fmt::format("({}, {})", number(r[key][0], 4), number(r[key][1], 4));
  };
  t.rows.push_back({text("himmelblau.row.end_point"), text("himmelblau.row.end_point.paper"),
                    point(ref, "endpoint"), "–",
                    cell(run, [&](const json& r) { return point(r, "end_point"); }), "–", "–"});
  if (many)
    t.rows.push_back(
        cost_row(many,
                 text.format("himmelblau.row.cost_many",
                             fmt::arg("runs", get(many->at("settings"), "runs").get<int>())),
                 "–"));
  return t;
}

}  // namespace

void himmelblau_section(Document& doc, const json& results, const Numbers& numbers,
                        const std::filesystem::path& dir) {
  const json& paper = numbers.paper["table4"];
  const json& ref = numbers.reference["himmelblau"];
  const Text& text = numbers.text;
  doc.heading(2, text("himmelblau.heading"));
  experiment_status(doc, results, text, "himmelblau");
  const json* run = find_run(results, "himmelblau", [](const json&) { return true; });
  // A larger run, when the plan has one, for a tighter Ĉ than the paper's 70 runs allow.
  const json* many =
      find_run(results, "himmelblau", [&](const json& s) { return s.value("runs", 0) >= 400; });
  doc.table(himmelblau_table(run, many != run ? many : nullptr, paper, ref, text));
  Table paper_runs;
  paper_runs.caption = text("himmelblau.paper_runs.caption");
  paper_runs.header = {text("himmelblau.paper_runs.col.k"),
                       text("himmelblau.paper_runs.col.newton")};
  for (int i = 1; i <= 5; ++i)
    paper_runs.header.push_back(text.format("himmelblau.paper_runs.col.run", fmt::arg("i", i)));
  for (std::size_t k = 0; k < 20; ++k) {
    std::vector<std::string> row{std::to_string(k), at(paper["newton"], k, 2)};
    for (const auto& r : paper["runs"]) row.push_back(at(r, k, 2));
    paper_runs.rows.push_back(row);
  }
  doc.table(paper_runs);
  const auto csv = dir / "table4_himmelblau.csv";
  if (ok(run) && std::filesystem::exists(csv)) {
    try {
      Table ours = read_csv_table(csv);
      ours.caption = text("himmelblau.ours.caption");
      for (auto& row : ours.rows)
        for (auto& c : row) {
          char* end = nullptr;
          const double v = std::strtod(c.c_str(), &end);
          if (end && *end == '\0' && !c.empty() && c.find('.') != std::string::npos)
            c = fmt::format("{:.2f}", v);
        }
      doc.table(ours);
    } catch (const std::exception& e) {
      doc.paragraph(text.format("himmelblau.ours.unreadable", fmt::arg("error", e.what())));
    }
  }
  figure(doc, results, text, 5, "himmelblau.figure5");
  doc.heading(3, text("differences.heading"));
  doc.list(text.items("himmelblau.differences"));
  settings_list(doc, results, text, "himmelblau");
}

}  // namespace implicit::app::report::parts
