// Double slit experiment (paper §3.1: Table 2, Figures 1 and 2; spec §2.4).
//
// Table 2: closed-loop runs of spec §2.4.6 (exact and implicit-sampling controllers driven by
// the same noise), in parallel over runs. Figure 1: plain Monte Carlo walks and guided walks of
// implicit sampling from x(0) = 1. Figure 2: one run's trajectory and control.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/os.h>

#include "experiments/control.hpp"
#include "experiments/parallel_runs.hpp"
#include "experiments/slit_table.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"

namespace implicit::experiments {

namespace {

// Figure 1 (left): the first `count` plain Monte Carlo walks up to the wall, every 2nd step.
void write_unguided(OutputFile& out, const control::DoubleSlit& slit,
                    const Eigen::MatrixXd& walks) {
  out.print("path,t,x\n");
  for (Eigen::Index j = 0; j < walks.cols(); ++j)
    for (int k = 0; k <= slit.wall_step(); k += 2)
      out.print("{},{:.3f},{:.5f}\n", j, slit.time(k), walks(k, j));
}

// Figure 1 (right): M guided walks of implicit sampling at (x(0), t = 0), dominant slit.
void write_guided(OutputFile& out, const control::DoubleSlit& slit, int M, std::uint64_t seed) {
  const double x0 = slit.parameters().initial_state;
  const auto left = slit.constrained_minimum(x0, 0, 0), right = slit.constrained_minimum(x0, 0, 1);
  const int s = left.phi <= right.phi ? 0 : 1;
  const int n = slit.num_steps();
  Rng rng({seed, 0, 0, purpose::kUser + 1});
  Eigen::MatrixXd xi(n, M), paths;
  rng.fill_normal(xi);
  const auto lw = slit.path_log_weights(x0, 0, s, xi, nullptr, &paths);
  out.print("path,t,x,passed\n");
  for (int j = 0; j < M; ++j) {
    const int passed = std::isfinite(lw[static_cast<std::size_t>(j)]) ? 1 : 0;
    out.print("{},{:.3f},{:.6f},{}\n", j, 0.0, x0, passed);
    for (int i = 1; i <= n; ++i)
      out.print("{},{:.3f},{:.6f},{}\n", j, slit.time(i), paths(i - 1, j), passed);
  }
}

void write_run(OutputFile& out, const control::DoubleSlit& slit, const control::SlitRun& run) {
  out.print("t,x_exact,x_implicit,u_exact,u_implicit\n");
  const int K = slit.num_steps();
  for (int k = 0; k <= K; ++k) {
    if (k < K)
      out.print("{:.3f},{:.8f},{:.8f},{:.8f},{:.8f}\n", slit.time(k), run.x_exact(k),
                run.x_estimate(k), run.u_exact(k), run.u_estimate(k));
    else
      out.print("{:.3f},{:.8f},{:.8f},,\n", slit.time(k), run.x_exact(k), run.x_estimate(k));
  }
}

}  // namespace

nlohmann::json run_slit(const SlitSettings& s, const RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  require(s.samples >= 1, "slit --samples: expected at least 1, got {}", s.samples);
  require(s.runs >= 1, "slit --runs: expected at least 1, got {}", s.runs);
  require(s.naive_mc_small >= 1 && s.naive_mc_large >= 1,
          "slit naive Monte Carlo: expected positive path counts, got {} and {}", s.naive_mc_small,
          s.naive_mc_large);
  const control::DoubleSlit slit;  // Table 1
  const double x0 = slit.parameters().initial_state;

  // Table 2.
  SlitTableOptions opt;
  opt.samples = s.samples;
  opt.runs = s.runs;
  opt.estimator = s.mode;
  opt.seed = ctx.seed;
  opt.implementation = s.estimator;
  SlitTable table;
  {
    ProgressBar progress(fmt::format("slit {} M={}", name_of(s.mode), s.samples),
                         static_cast<std::size_t>(s.runs), ctx.show_progress());
    auto rows = distribute_runs(ctx, "slit",
                                fmt::format("seed={} M={} mode={} estimator={}", ctx.seed,
                                            s.samples, name_of(s.mode), name_of(s.estimator)),
                                static_cast<std::size_t>(s.runs), [&](std::size_t r) {
                                  SlitTableRow row = slit_table_row(slit, opt, r);
                                  progress.tick();
                                  return row;
                                });
    table = summarise_slit_table(std::move(rows));
    progress.finish();
  }

  // Plain Monte Carlo (Figure 1 left): how many unguided walks pass the wall.
  Eigen::MatrixXd walks;
  const auto small =
      slit.plain_monte_carlo(x0, 0, s.naive_mc_small, ctx.seed, 1,
                             ctx.out_dir.empty() ? nullptr : &walks, s.naive_mc_small);
  const auto large = slit.plain_monte_carlo(x0, 0, s.naive_mc_large, ctx.seed, 2);

  if (!ctx.out_dir.empty()) {
    // Every file is written under a temporary name and renamed only when all are complete.
    OutputFile unguided(ctx.csv_path("figure1_unguided.csv"));
    OutputFile guided(ctx.csv_path("figure1_guided.csv"));
    OutputFile figure2(ctx.csv_path("figure2_slit.csv"));
    write_unguided(unguided, slit, walks);
    write_guided(guided, slit, 50, ctx.seed);
    const auto run0 = slit_run(slit, opt, 0);
    write_run(figure2, slit, run0);
    OutputFile out(ctx.csv_path(fmt::format("slit_runs_{}_M{}.csv", name_of(s.mode), s.samples)));
    out.print("run,error_x,error_u,crashed_exact,crashed_implicit,fallbacks,ess_mean\n");
    for (std::size_t r = 0; r < table.runs.size(); ++r) {
      const auto& row = table.runs[r];
      out.print("{},{:.8g},{:.8g},{},{},{},{:.4f}\n", r, row.error_x, row.error_u,
                row.crashed_exact ? 1 : 0, row.crashed_estimate ? 1 : 0, row.fallbacks,
                row.ess_mean);
    }
    for (OutputFile* f : {&unguided, &guided, &figure2, &out}) f->commit();
  }

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {
      {"samples", s.samples},
      {"runs", s.runs},
      {"mode", name_of(s.mode)},
      {"estimator", name_of(s.estimator)},
      {"error_x_mean", 100.0 * table.error_x_mean},
      {"error_x_std", 100.0 * table.error_x_std},
      {"error_x_median", 100.0 * table.error_x_median},
      {"error_u_mean", 100.0 * table.error_u_mean},
      {"error_u_std", 100.0 * table.error_u_std},
      {"error_u_median", 100.0 * table.error_u_median},
      {"crash_fraction", table.crash_fraction},
      {"exact_crash_fraction", table.exact_crash_fraction},
      {"fallbacks", table.fallbacks},
      {"ess_mean", table.ess_mean},
      {"naive_mc_samples", large.paths},
      {"naive_mc_passed", large.passed},
      {"naive_mc_small_samples", small.paths},
      {"naive_mc_small_passed", small.passed},
      {"seed", ctx.seed},
      {"threads", active_threads()},
      {"seconds", seconds},
  };
}

}  // namespace implicit::experiments
