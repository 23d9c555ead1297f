// `implicit himmelblau`: minimising Himmelblau's function by stochastic control (paper §3.3).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments.hpp"
#include "implicit/core/parallel.hpp"
#include "plural.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct HimmelblauCommand {
  HimmelblauSettings settings;
  RunContext ctx;
  bool allow_empty = false;
};

void setup_himmelblau(CLI::App& sub) {
  auto cmd = std::make_shared<HimmelblauCommand>();
  sub.add_option("--runs", cmd->settings.runs, "Independent controlled runs")
      ->check(in_range(1, 1000000))
      ->capture_default_str();
  sub.add_option("--samples,-M", cmd->settings.samples, "Samples M per psi estimate")
      ->check(in_range(1, 1000000))
      ->capture_default_str();
  sub.add_flag("--allow-empty", cmd->allow_empty,
               "Exit 0 even when a metric is not finite; a warning is printed either way");
  add_common_options(sub, cmd->ctx);
  sub.callback([cmd] {
    ThreadLimit limit(cmd->ctx.threads);
    const auto r = run_himmelblau(cmd->settings, cmd->ctx);
    const auto check = [&] {
      require_scored(r, "himmelblau",
                     {"mean_cost", "mean_final_f", "mean_f_before_last_step", "newton_final_f"}, {},
                     cmd->allow_empty);
    };
    if (cmd->ctx.json) {
      print_json(r);
      check();
      return;
    }
    fmt::print(
        "Himmelblau from (-1, -4), {}, M = {}:\n"
        "  Newton stops at f = {:.4f} (a saddle)\n"
        "  runs ending with f < 10: {} of {}; mean final f {:.3f}; mean cost {:.3f} ± {:.3f}\n"
        "  mean end point ({:.4f}, {:.4f})\n"
        "  closed form: cost {:.4f}, f(x_19) {:.3f}; ours: f(x_19) {:.3f} ± {:.3f}, cost with the "
        "last noise step averaged {:.5f} ± {:.5f}\n"
        "  {:.2f} s\n",
        counted(r["runs"].get<int>(), "run", "runs"), r["samples"].get<int>(),
        r["newton_final_f"].get<double>(), r["runs_below_10"].get<int>(), r["runs"].get<int>(),
        r["mean_final_f"].get<double>(), r["mean_cost"].get<double>(),
        r["mean_cost_se"].get<double>(), r["end_point"][0].get<double>(),
        r["end_point"][1].get<double>(), r["expected"]["cost"].get<double>(),
        r["expected"]["f_before_last_step"].get<double>(),
        r["mean_f_before_last_step"].get<double>(), r["mean_f_before_last_step_se"].get<double>(),
        r["mean_cost_last_step_adjusted"].get<double>(),
        r["mean_cost_last_step_adjusted_se"].get<double>(), r["seconds"].get<double>());
    check();
  });
}

const Registrar register_himmelblau{
    "himmelblau", "Himmelblau's function minimised by stochastic control", setup_himmelblau};

}  // namespace
}  // namespace implicit::app
