// `implicit slit`: the double slit experiment (paper §3.1, Table 2, Figures 1-2).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments.hpp"
#include "implicit/core/parallel.hpp"
#include "plural.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct SlitCommand {
  SlitSettings settings;
  std::string mode = "corrected", estimator = "generic";  ///< parsed by experiments/choices.hpp
  RunContext ctx;
  bool allow_empty = false;
};

void setup_slit(CLI::App& sub) {
  auto cmd = std::make_shared<SlitCommand>();
  sub.add_option("--samples,-M", cmd->settings.samples, "Samples M per psi estimate (per slit)")
      ->check(in_range(1, 1000000))
      ->capture_default_str();
  sub.add_option("--runs", cmd->settings.runs, "Closed-loop runs (Table 2)")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--mode", cmd->mode,
                 "paper: the paper's estimator (biased, reproduces Table 2); corrected: unbiased "
                 "weights with the frozen wall; plain: unbiased weights, plain FD")
      ->check(CLI::IsMember({"paper", "corrected", "plain"}))
      ->capture_default_str();
  sub.add_option("--estimator", cmd->estimator,
                 "generic: the library's path integral estimator on the double slit as a "
                 "ControlProblem; wall-space: the double slit's own estimator, which samples the "
                 "wall value alone (the same runs to rounding, faster)")
      ->check(CLI::IsMember({"generic", "wall-space"}))
      ->capture_default_str();
  sub.add_option("--naive-small", cmd->settings.naive_mc_small,
                 "Plain Monte Carlo walks written for Figure 1")
      ->check(in_range(1, 10000000))
      ->capture_default_str();
  sub.add_option("--naive-large", cmd->settings.naive_mc_large,
                 "Plain Monte Carlo walks counted for the pass rate")
      ->check(in_range(1, 100000000))
      ->capture_default_str();
  sub.add_flag("--allow-empty", cmd->allow_empty,
               "Exit 0 even when a metric is not finite; a warning is printed either way");
  add_common_options(sub, cmd->ctx);
  sub.callback([cmd] {
    ThreadLimit limit(cmd->ctx.threads);
    cmd->settings.mode = experiments::parse_slit_mode(cmd->mode);
    cmd->settings.estimator = experiments::parse_slit_estimator(cmd->estimator);
    const auto r = run_slit(cmd->settings, cmd->ctx);
    const auto check = [&] {
      require_scored(r, "slit", {"error_x_mean", "error_u_mean", "crash_fraction"}, {},
                     cmd->allow_empty);
    };
    if (cmd->ctx.json) {
      print_json(r);
      check();
      return;
    }
    fmt::print(
        "double slit, mode {}, M = {}, {}:\n"
        "  e_x = {:.2f} ± {:.2f} % (median {:.2f})\n"
        "  e_u = {:.2f} ± {:.2f} % (median {:.2f})\n"
        "  crash fraction {:.3f} (exact control {:.3f})\n"
        "  plain Monte Carlo: {} of {} walks pass the wall\n"
        "  {:.1f} s\n",
        r["mode"].get<std::string>(), r["samples"].get<int>(),
        counted(r["runs"].get<int>(), "run", "runs"), r["error_x_mean"].get<double>(),
        r["error_x_std"].get<double>(), r["error_x_median"].get<double>(),
        r["error_u_mean"].get<double>(), r["error_u_std"].get<double>(),
        r["error_u_median"].get<double>(), r["crash_fraction"].get<double>(),
        r["exact_crash_fraction"].get<double>(), r["naive_mc_passed"].get<int>(),
        r["naive_mc_samples"].get<int>(), r["seconds"].get<double>());
    check();
  });
}

const Registrar register_slit{
    "slit", "Double slit: path integral control through a wall (paper Table 2)", setup_slit};

}  // namespace
}  // namespace implicit::app
