// Himmelblau experiment (paper §3.3, Table 4, Figure 5; spec §2.6): Newton's method from
// (-1, -4) stops at a saddle (f = 178.34); receding-horizon path integral control with implicit
// sampling escapes it. Runs are independent and run in parallel (streams keyed by run).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/os.h>

#include "experiments/control.hpp"
#include "experiments/parallel_runs.hpp"
#include "implicit/control/himmelblau.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"

namespace implicit::experiments {
namespace {

HimmelblauRunRecord to_record(const control::HimmelblauRun& run) {
  HimmelblauRunRecord r;
  r.cost = run.cost;
  r.final_f = run.final_f;
  r.ess_mean = run.ess_mean;
  r.failed_minimizations = run.failed_minimizations;
  r.last_noise_1 = run.last_noise(0);
  r.last_noise_2 = run.last_noise(1);
  r.max_laplace_gap = run.max_laplace_gap;
  for (const auto& v : run.x) r.x.insert(r.x.end(), {v(0), v(1)});
  for (const auto& v : run.u) r.u.insert(r.u.end(), {v(0), v(1)});
  return r;
}

control::HimmelblauRun from_record(const HimmelblauRunRecord& r) {
  control::HimmelblauRun run;
  run.cost = r.cost;
  run.final_f = r.final_f;
  run.ess_mean = r.ess_mean;
  run.failed_minimizations = r.failed_minimizations;
  run.last_noise = Vec<2>(r.last_noise_1, r.last_noise_2);
  run.max_laplace_gap = r.max_laplace_gap;
  for (std::size_t k = 0; k + 1 < r.x.size(); k += 2) run.x.emplace_back(r.x[k], r.x[k + 1]);
  for (std::size_t k = 0; k + 1 < r.u.size(); k += 2) run.u.emplace_back(r.u[k], r.u[k + 1]);
  return run;
}

/// Table 4 and Figure 5's data: f along the Newton path and the first runs, and every run's path.
void write_himmelblau_csv(const RunContext& ctx, const HimmelblauSettings& s, int K,
                          const std::vector<Vec<2>>& newton,
                          const std::vector<control::HimmelblauRun>& runs) {
  // The three files are renamed into place together, once all are written.
  OutputFile table4(ctx.csv_path("table4_himmelblau.csv"));
  OutputFile newton_csv(ctx.csv_path("figure5_newton.csv"));
  OutputFile runs_csv(ctx.csv_path("figure5_runs.csv"));
  {
    OutputFile& out = table4;
    out.print("k,newton");
    const int shown = std::min(5, s.runs);
    for (int r = 0; r < shown; ++r) out.print(",run{}", r + 1);
    out.print("\n");
    for (int k = 0; k <= K; ++k) {
      out.print("{}", k);
      if (k < static_cast<int>(newton.size()))
        out.print(",{:.4f}", control::himmelblau(newton[static_cast<std::size_t>(k)]));
      else
        out.print(",");
      for (int r = 0; r < shown; ++r)
        out.print(",{:.4f}", control::himmelblau(runs[static_cast<std::size_t>(r)].x[k]));
      out.print("\n");
    }
  }
  {
    OutputFile& out = newton_csv;
    out.print("k,x1,x2,f\n");
    for (std::size_t k = 0; k < newton.size(); ++k)
      out.print("{},{:.10f},{:.10f},{:.10f}\n", k, newton[k](0), newton[k](1),
                control::himmelblau(newton[k]));
  }
  {
    OutputFile& out = runs_csv;
    out.print("run,k,x1,x2,f\n");
    for (std::size_t r = 0; r < runs.size(); ++r)
      for (std::size_t k = 0; k < runs[r].x.size(); ++k)
        out.print("{},{},{:.10f},{:.10f},{:.10f}\n", r, k, runs[r].x[k](0), runs[r].x[k](1),
                  control::himmelblau(runs[r].x[k]));
  }
  for (OutputFile* f : {&table4, &newton_csv, &runs_csv}) f->commit();
}

}  // namespace

nlohmann::json run_himmelblau(const HimmelblauSettings& s, const RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  require(s.runs >= 1, "himmelblau --runs: expected at least 1, got {}", s.runs);
  require(s.samples >= 1, "himmelblau --samples: expected at least 1, got {}", s.samples);
  const control::HimmelblauProblem pb;  // R = sigma = 0.01, dt = 1, tf = 20, x0 = (-1, -4)
  const int K = pb.num_steps();
  const auto newton = control::himmelblau_newton(pb.x0, 7);

  std::vector<control::HimmelblauRun> runs(static_cast<std::size_t>(s.runs));
  {
    ProgressBar progress(fmt::format("himmelblau M={}", s.samples), runs.size(),
                         ctx.show_progress());
    const auto records = distribute_runs(
        ctx, "himmelblau", fmt::format("seed={} M={}", ctx.seed, s.samples), runs.size(),
        [&](std::size_t r) {
          auto record = to_record(control::simulate_himmelblau_run(pb, s.samples, ctx.seed, r));
          progress.tick();
          return record;
        });
    for (std::size_t r = 0; r < runs.size(); ++r) runs[r] = from_record(records[r]);
    progress.finish();
  }
  // Closed-form expectations (discrete Brownian bridge to x*, see himmelblau_bridge_reference)
  // and the cost with the uncontrollable last noise step replaced by its expectation: with an
  // sd of ~1e-3 instead of ~1.07 it shows whether the controls are right even for 70 runs.
  const auto ref = control::himmelblau_bridge_reference(pb);
  int below = 0, failed = 0;
  double ess = 0.0, max_gap = 0.0;
  std::vector<double> cost, adjusted, f19, final_f;
  Vec<2> end = Vec<2>::Zero();
  for (const auto& r : runs) {
    below += r.final_f < 10.0 ? 1 : 0;
    failed += r.failed_minimizations;
    cost.push_back(r.cost);
    adjusted.push_back(control::last_step_adjusted_cost(pb, r, ref));
    f19.push_back(control::himmelblau(r.x[static_cast<std::size_t>(K - 1)]));
    final_f.push_back(r.final_f);
    ess += r.ess_mean / s.runs;
    max_gap = std::max(max_gap, r.max_laplace_gap);
    end += r.x.back() / s.runs;
  }
  // Mean and standard error over the runs (SE 0 for a single run).
  auto mean_se = [](const std::vector<double>& v) {
    const double n = static_cast<double>(v.size());
    double m = 0.0, q = 0.0;
    for (double x : v) m += x / n;
    for (double x : v) q += (x - m) * (x - m);
    return std::pair{m, v.size() > 1 ? std::sqrt(q / (n - 1.0) / n) : 0.0};
  };
  const auto [mean_cost, cost_se] = mean_se(cost);
  const auto [mean_adjusted, adjusted_se] = mean_se(adjusted);
  const auto [mean_f19, f19_se] = mean_se(f19);
  const auto [mean_f, final_f_se] = mean_se(final_f);

  if (!ctx.out_dir.empty()) write_himmelblau_csv(ctx, s, K, newton, runs);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {
      {"runs", s.runs},
      {"samples", s.samples},
      {"runs_below_10", below},
      {"mean_cost", mean_cost},
      {"mean_cost_se", cost_se},
      {"mean_cost_last_step_adjusted", mean_adjusted},
      {"mean_cost_last_step_adjusted_se", adjusted_se},
      {"mean_final_f", mean_f},
      {"mean_final_f_se", final_f_se},
      {"mean_f_before_last_step", mean_f19},
      {"mean_f_before_last_step_se", f19_se},
      {"expected",
       {{"cost", ref.cost()},
        {"control_cost", ref.control_cost},
        {"final_f", ref.final_f},
        {"f_before_last_step", ref.f_before_last_step}}},
      {"max_control_minus_laplace", max_gap},
      {"newton_final_f", control::himmelblau(newton.back())},
      {"end_point", {end(0), end(1)}},
      {"ess_mean", ess},
      {"failed_minimizations", failed},
      {"seed", ctx.seed},
      {"seconds", seconds},
  };
}

}  // namespace implicit::experiments
