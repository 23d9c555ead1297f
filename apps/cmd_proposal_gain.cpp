// `implicit proposal-gain`: implicit against bootstrap MCL on simulated logs, over the ratio of
// per-step process noise to sensor noise and over the step length (docs/user-guide.md, "Which
// proposal should I use?").
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments.hpp"
#include "implicit/core/parallel.hpp"
#include "plural.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct ProposalGainCommand {
  ProposalGainSettings settings;
  RunContext ctx;
};

void print_gain_text(const nlohmann::json& r) {
  fmt::print("implicit vs bootstrap MCL, M = {}, {} of {} s per point\n", r["particles"].get<int>(),
             counted(r["runs"].get<int>(), "simulated log", "simulated logs"),
             r["duration_s"].get<double>());
  fmt::print("{:<6} {:>6} {:>7} {:>15} {:>15} {:>15} {:>15} {:>9} {:>9}\n", "sweep", "dt", "ratio",
             "ESS/M impl", "ESS/M boot", "RMSE impl [m]", "RMSE boot [m]", "cpu impl", "cpu boot");
  for (const auto& p : r["points"]) {
    const auto& i = p["implicit"];
    const auto& b = p["standard"];
    fmt::print(
        "{:<6} {:>6.3f} {:>7.3f} {:>7.3f}±{:<7.3f} {:>7.3f}±{:<7.3f} {:>7.3f}±{:<7.3f} "
        "{:>7.3f}±{:<7.3f} {:>9.4f} {:>9.4f}\n",
        p["sweep"].get<std::string>(), p["dt"].get<double>(), p["ratio"].get<double>(),
        i["ess"].get<double>(), i["ess_se"].get<double>(), b["ess"].get<double>(),
        b["ess_se"].get<double>(), i["rmse_m"].get<double>(), i["rmse_m_se"].get<double>(),
        b["rmse_m"].get<double>(), b["rmse_m_se"].get<double>(), i["cpu_ms_per_step"].get<double>(),
        b["cpu_ms_per_step"].get<double>());
  }
  if (r.contains("carpark_ratio"))
    fmt::print("Car Park noise ratio: config A {:.3f}, config B {:.3f}\n",
               r["carpark_ratio"]["A"].get<double>(), r["carpark_ratio"]["B"].get<double>());
  fmt::print("(± one standard error over the logs; cpu in ms per step)\n{:.1f} s\n",
             r["seconds"].get<double>());
}

void setup_proposal_gain(CLI::App& sub) {
  auto cmd = std::make_shared<ProposalGainCommand>();
  auto& s = cmd->settings;
  sub.add_option("--particles,-M", s.particles, "Particles M of both filters")
      ->check(in_range(1, 1000000))
      ->capture_default_str();
  sub.add_option("--runs", s.runs, "Simulated logs per point (both proposals run on each)")
      ->check(in_range(1, 1000000))
      ->capture_default_str();
  sub.add_option("--duration", s.duration, "Seconds simulated per log (unicycle at 1 m/s)")
      ->check(in_range(0.1, 1e5))
      ->capture_default_str();
  sub.add_option("--ratio-dt", s.ratio_dt, "Step length [s] of the noise-ratio sweep")
      ->check(in_range(1e-3, 10.0))
      ->capture_default_str();
  sub.add_option("--ratios", s.ratios,
                 "Per-step process position sd / sensor range sd, one point each (the sensor "
                 "noise is scaled, the motion noise is the unicycle's default)")
      ->delimiter(',')
      ->check(in_range(1e-6, 1e6));
  sub.add_option("--dts", s.dts, "Step lengths [s] of the step-length sweep")
      ->delimiter(',')
      ->check(in_range(1e-3, 10.0));
  sub.add_option("--dt-range-sd", s.dt_range_sd, "Sensor range sd [m] of the step-length sweep")
      ->check(in_range(1e-6, 100.0))
      ->capture_default_str();
  add_common_options(sub, cmd->ctx);
  set_examples(sub, {"implicit proposal-gain --runs 4 --duration 12",
                     "implicit proposal-gain --ratios 1,10 --dts 0.1 --runs 10 --json",
                     "implicit proposal-gain --out gain/   # writes gain/proposal_gain.csv"});
  sub.callback([cmd] {
    ThreadLimit limit(cmd->ctx.threads);
    const auto r = run_proposal_gain(cmd->settings, cmd->ctx);
    if (cmd->ctx.json)
      print_json(r);
    else
      print_gain_text(r);
  });
}

const Registrar register_proposal_gain{
    "proposal-gain", "When implicit MCL beats bootstrap MCL: noise ratio and step length sweeps",
    setup_proposal_gain};

}  // namespace
}  // namespace implicit::app
