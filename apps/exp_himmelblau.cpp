// Himmelblau experiment (paper §3.3, Table 4, Figure 5; spec §2.6): Newton's method from
// (-1, -4) stops at a saddle (f = 178.34); receding-horizon path integral control with implicit
// sampling escapes it. Runs are independent and run in parallel (streams keyed by run).
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <fmt/os.h>

#include "experiments.hpp"
#include "implicit/control/himmelblau.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"

namespace implicit::app {

nlohmann::json run_himmelblau(const HimmelblauSettings& s, const RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  require(s.runs >= 1, "himmelblau --runs: expected at least 1, got {}", s.runs);
  require(s.samples >= 1, "himmelblau --samples: expected at least 1, got {}", s.samples);
  const control::HimmelblauProblem pb;  // R = sigma = 0.01, dt = 1, tf = 20, x0 = (-1, -4)
  const int K = pb.num_steps();
  const auto newton = control::himmelblau_newton(pb.x0, 7);

  std::vector<control::HimmelblauRun> runs(static_cast<std::size_t>(s.runs));
  {
    Progress progress(fmt::format("himmelblau M={}", s.samples), runs.size(), ctx.show_progress());
    parallel_for(
        runs.size(),
        [&](std::size_t r) {
          runs[r] = control::simulate_himmelblau_run(pb, s.samples, ctx.seed, r);
          progress.tick();
        },
        1);
    progress.finish();
  }
  int below = 0, failed = 0;
  double mean_cost = 0.0, mean_f = 0.0, mean_f19 = 0.0, ess = 0.0;
  Vec<2> end = Vec<2>::Zero();
  for (const auto& r : runs) {
    below += r.final_f < 10.0 ? 1 : 0;
    failed += r.failed_minimizations;
    mean_cost += r.cost / s.runs;
    mean_f += r.final_f / s.runs;
    mean_f19 += control::himmelblau(r.x[static_cast<std::size_t>(K - 1)]) / s.runs;
    ess += r.ess_mean / s.runs;
    end += r.x.back() / s.runs;
  }
  double var = 0.0;
  for (const auto& r : runs) var += (r.cost - mean_cost) * (r.cost - mean_cost);
  const double cost_se = s.runs > 1 ? std::sqrt(var / (s.runs - 1) / s.runs) : 0.0;

  if (!ctx.out_dir.empty()) {
    {
      auto out = fmt::output_file(ctx.csv_path("table4_himmelblau.csv").string());
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
      auto out = fmt::output_file(ctx.csv_path("figure5_newton.csv").string());
      out.print("k,x1,x2,f\n");
      for (std::size_t k = 0; k < newton.size(); ++k)
        out.print("{},{:.10f},{:.10f},{:.10f}\n", k, newton[k](0), newton[k](1),
                  control::himmelblau(newton[k]));
    }
    {
      auto out = fmt::output_file(ctx.csv_path("figure5_runs.csv").string());
      out.print("run,k,x1,x2,f\n");
      for (std::size_t r = 0; r < runs.size(); ++r)
        for (std::size_t k = 0; k < runs[r].x.size(); ++k)
          out.print("{},{},{:.10f},{:.10f},{:.10f}\n", r, k, runs[r].x[k](0), runs[r].x[k](1),
                    control::himmelblau(runs[r].x[k]));
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {
      {"runs", s.runs},
      {"samples", s.samples},
      {"runs_below_10", below},
      {"mean_cost", mean_cost},
      {"mean_cost_se", cost_se},
      {"mean_final_f", mean_f},
      {"mean_f_before_last_step", mean_f19},
      {"newton_final_f", control::himmelblau(newton.back())},
      {"end_point", {end(0), end(1)}},
      {"ess_mean", ess},
      {"failed_minimizations", failed},
      {"seed", ctx.seed},
      {"seconds", seconds},
  };
}

}  // namespace implicit::app
