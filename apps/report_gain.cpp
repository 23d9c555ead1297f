// The report's section beyond the paper: when the implicit proposal beats the bootstrap proposal
// in MCL (experiments/proposal_gain.cpp), with the Car Park configurations as two real points.
#include <cmath>

#include <fmt/format.h>

#include "report_parts.hpp"

namespace implicit::app::report::parts {

namespace {

std::string mean_se_text(const json& c, const std::string& key, int digits) {
  if (!c.is_object() || !c.contains(key) || !c.contains(key + "_se")) return "—";
  return fmt::format("{:.{}f} ± {:.{}f}", c[key].get<double>(), digits,
                     c[key + "_se"].get<double>(), digits);
}

/// The mcl run with M = 100 of `config` and `method` (the Car Park points), or null.
const json* carpark_run(const json& results, const std::string& config, const std::string& method) {
  return find_run(results, "mcl", [&](const json& s) {
    return s.value("config", std::string()) == config &&
           s.value("method", std::string()) == method && s.value("particles", 0) == 100 &&
           s.value("p", -1.0) < 0;
  });
}

Table simulated_table(const json& result, const Text& text) {
  Table t;
  t.header = {text("gain.col.sweep"),          text("gain.col.dt"),
              text("gain.col.noise_ratio"),    text("gain.col.ess_implicit"),
              text("gain.col.ess_bootstrap"),  text("gain.col.rmse_implicit"),
              text("gain.col.rmse_bootstrap"), text("gain.col.cpu_implicit"),
              text("gain.col.cpu_bootstrap")};
  for (const auto& p : result.value("points", json::array())) {
    t.rows.push_back({p.value("sweep", std::string()), fmt::format("{:g}", p.value("dt", 0.0)),
                      fmt::format("{:.3g}", p.value("ratio", 0.0)),
                      mean_se_text(p["implicit"], "ess", 3), mean_se_text(p["standard"], "ess", 3),
                      mean_se_text(p["implicit"], "rmse_m", 3),
                      mean_se_text(p["standard"], "rmse_m", 3),
                      mean_se_text(p["implicit"], "cpu_ms_per_step", 4),
                      mean_se_text(p["standard"], "cpu_ms_per_step", 4)});
  }
  return t;
}

Table carpark_table(const json& results, const json& result, const Text& text) {
  Table t;
  t.header = {text("gain.col.carpark_config"), text("gain.col.noise_ratio"),
              text("gain.col.ess_implicit"),   text("gain.col.ess_bootstrap"),
              text("gain.col.rmse_implicit"),  text("gain.col.rmse_bootstrap")};
  for (const std::string config : {"A", "B"}) {
    const json* im = carpark_run(results, config, "implicit");
    const json* bs = carpark_run(results, config, "standard");
    const auto& ratio = get(get(result, "carpark_ratio"), config);
    auto show = [](const json* run, const std::string& key, const std::string& sd) {
      return cell(run, [&](const json& r) {
        const double n = std::sqrt(r.value("runs", 1.0));
        return fmt::format("{:.3f} ± {:.3f}", r.value(key, 0.0), r.value(sd, 0.0) / n);
      });
    };
    t.rows.push_back({config, ratio.is_number() ? fmt::format("{:.3f}", ratio.get<double>()) : "—",
                      show(im, "ess_mean", "ess_std"), show(bs, "ess_mean", "ess_std"),
                      show(im, "rmse_m", "rmse_m_std"), show(bs, "rmse_m", "rmse_m_std")});
  }
  return t;
}

}  // namespace

void proposal_gain_section(Document& doc, const json& results, const Numbers& numbers) {
  const Text& text = numbers.text;
  doc.heading(2, text("gain.heading"));
  experiment_status(doc, results, text, "proposal_gain");
  doc.paragraph(text("gain.intro"));
  const json* run = find_run(results, "proposal_gain", [](const json&) { return true; });
  if (ok(run)) {
    const json& r = run->at("result");
    doc.table(simulated_table(r, text));
    doc.table(carpark_table(results, r, text));
  }
  figure(doc, results, text, 8, "gain.figure8");
  settings_list(doc, results, text, "proposal_gain");
}

}  // namespace implicit::app::report::parts
