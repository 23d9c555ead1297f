// `implicit da`: one ensemble filter (bootstrap or implicit particle filter, EnKF, ETKF) on the
// Lorenz-63 or Lorenz-96 benchmark setting, rmse.a over seeds (docs/cli.md, "implicit da").
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments/choices.hpp"
#include "experiments/da.hpp"
#include "implicit/core/parallel.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct DaCommand {
  experiments::DaSettings settings;
  RunContext ctx;
};

void print_da_text(const nlohmann::json& r) {
  fmt::print("{} ({}, n = {}), {} N = {}, {} seeds from {}\n", r["model"].get<std::string>(),
             r["setting"].get<std::string>(), r["dim"].get<int>(), r["method"].get<std::string>(),
             r["members"].get<int>(), r["seeds"].get<int>(), r["seed"].get<std::uint64_t>());
  const auto& rm = r["rmse_a"];
  if (r["diverged_runs"].get<int>() > 0)
    fmt::print("rmse.a   undefined: a run diverged (below)\n");
  else if (rm["ci95"].is_null())
    fmt::print("rmse.a   {:.4f}\n", rm["mean"].get<double>());
  else
    fmt::print("rmse.a   {:.4f}  95% CI [{:.4f}, {:.4f}]\n", rm["mean"].get<double>(),
               rm["ci95"][0].get<double>(), rm["ci95"][1].get<double>());
  fmt::print("spread.a {:.4f}\nmean ESS {:.1f}\n{:.3f} ms per cycle, {:.1f} s\n",
             r["spread_a"].get<double>(), r["mean_ess"].get<double>(),
             r["ms_per_cycle"].get<double>(), r["seconds"].get<double>());
}

/// A run whose filter diverged has no rmse.a: stderr names the runs, and the exit code is 1.
void report_divergence(const nlohmann::json& r) {
  const int diverged = r["diverged_runs"].get<int>();
  if (diverged == 0) return;
  std::string runs;
  for (const auto& run : r["runs"])
    if (run["diverged_at_cycle"].is_number())
      runs += fmt::format("{}seed {} at cycle {}", runs.empty() ? "" : ", ",
                          run["seed"].get<std::uint64_t>(), run["diverged_at_cycle"].get<int>());
  fmt::print(stderr,
             "implicit da: error: {} of {} runs diverged (the analysis mean left the finite "
             "numbers: {}), so rmse.a is not defined; more members, inflation or jitter may keep "
             "the filter on track\n",
             diverged, r["seeds"].get<int>(), runs);
  throw CLI::RuntimeError(1);
}

void setup_da(CLI::App& sub) {
  auto cmd = std::make_shared<DaCommand>();
  auto& s = cmd->settings;
  sub.add_option("--model", s.model,
                 "lorenz63 (setting sakov2012) or lorenz96 (setting bocquet2010)")
      ->check(CLI::IsMember({"lorenz63", "lorenz96"}))
      ->capture_default_str();
  sub.add_option("--dim", s.dim, "Lorenz-96 dimension n")
      ->check(in_range(4, 100000))
      ->capture_default_str();
  sub.add_option("--forcing", s.forcing, "Lorenz-96 forcing F")
      ->check(in_range(-1e6, 1e6))
      ->capture_default_str();
  sub.add_option("--method", s.method, experiments::da_methods().help())
      ->check(CLI::IsMember(experiments::da_methods().names()))
      ->capture_default_str();
  sub.add_option("-N,--members", s.members, "Ensemble members / particles N")
      ->check(in_range(2, 10000000))
      ->capture_default_str();
  sub.add_option("--seeds", s.seeds, "Independent runs (seeds --seed, --seed + 1, ...)")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub.add_option("--jitter", s.jitter,
                 "Std (iso) or factor on Silverman's bandwidth (cov) of the Gaussian "
                 "regularisation: added after resampling (bootstrap), the model noise Q "
                 "(implicit)")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--regularisation", s.regularisation,
                 "Particle filters' regularisation: iso (jitter^2 I) or cov ((jitter h)^2 times "
                 "the weighted ensemble covariance, h Silverman's bandwidth)")
      ->check(CLI::IsMember({"iso", "cov"}))
      ->capture_default_str();
  sub.add_option("--inflation", s.inflation,
                 "Multiplicative inflation of the forecast anomalies "
                 "(enkf, etkf) or of the background's (implicit-smoother)")
      ->check(in_range(1.0, 1e3))
      ->capture_default_str();
  sub.add_option("--resample-threshold", s.resample_threshold,
                 "Resample when N_eff / N falls below this (particle filters)")
      ->check(in_range(0.0, 1.0))
      ->capture_default_str();
  sub.add_option("--map", s.map, "Implicit filter's map: linear or random")
      ->check(CLI::IsMember({"linear", "random"}))
      ->capture_default_str();
  sub.add_option("--lag", s.lag,
                 "implicit-smoother: window length L in observation cycles (default 3; refused "
                 "with the filters)")
      ->check(in_range(1, 1000));
  sub.add_option("--starts", s.starts,
                 "implicit-smoother: Newton starts per window, the background and the heaviest "
                 "members (default 3; refused with the filters)")
      ->check(in_range(1, 1000));
  sub.add_option("--bandwidth", s.bandwidth,
                 "implicit-smoother: kernel bandwidth h in (0, 1]; below 1 every member gets its "
                 "own kernel N(a x0_j + (1 - a) b, h^2 B) and Newton run (default 1: one Gaussian "
                 "background; refused with the filters)")
      ->check(in_range(0.0, 1.0));
  sub.add_option("--obs-every", s.obs_every,
                 "K: observe after every K-th model interval (the setting's interval each); "
                 "with --model-noise, where implicit and optimal-proposal sampling differ")
      ->check(in_range(1, 10000))
      ->capture_default_str();
  sub.add_option("--model-noise", s.model_noise,
                 "q: std of the model noise N(0, q^2 I) after every interval (0: deterministic)")
      ->check(in_range(0.0, 1e6))
      ->capture_default_str();
  sub.add_option("--cycles", s.cycles,
                 "Observation cycles (0: the setting's, 1000 or 1280, divided by --obs-every)")
      ->check(in_range(0, 100000000))
      ->capture_default_str();
  add_common_options(sub, cmd->ctx);
  set_examples(sub, {"implicit da --model lorenz63 --method etkf -N 10 --seeds 10",
                     "implicit da --method bootstrap -N 800 --jitter 0.3 --json",
                     "implicit da --model lorenz96 --dim 10 --method implicit -N 100 --jitter 0.2",
                     "implicit da --method implicit-smoother -N 30 --lag 3",
                     "implicit da --model lorenz96 --obs-every 4 --model-noise 0.5 --method "
                     "implicit -N 100"});
  sub.callback([cmd] {
    ThreadLimit limit(cmd->ctx.threads);
    const auto r = experiments::run_da(cmd->settings, cmd->ctx);
    if (cmd->ctx.json)
      print_json(r);
    else
      print_da_text(r);
    report_divergence(r);
  });
}

const Registrar register_da{
    "da",
    "Data assimilation: particle filters, EnKF, ETKF and the implicit smoother on Lorenz-63/96",
    setup_da};

}  // namespace
}  // namespace implicit::app
