#pragma once
// Table 2 of the paper (spec §2.4.6-2.4.7): many closed-loop runs of the double slit, summarised
// per estimator. The estimated trajectory is the library's generic closed loop
// (control::simulate_closed_loop) on the double slit as a ControlProblem resolved at the wall and
// the horizon (double_slit_problem.hpp); DoubleSlit's own wall-space estimator
// (control::simulate_slit_run) is the alternative, an independent check. The table is the
// experiment's.
//
//   experiments::SlitTableOptions o;                 // M = 50, 500 runs, corrected estimator, seed
//   1 const auto t = experiments::run_slit_table(control::DoubleSlit{}, o); t.error_u_mean;
//   t.crash_fraction;       // fractions, not %
//
// run_slit_table spreads the runs over the threads of one process; `implicit slit`
// (exp_slit.cpp) spreads the same rows over MPI ranks too (parallel_runs.hpp) and summarises
// them with the same function, so both give the same table.

#include <array>
#include <cstdint>
#include <vector>

#include "experiments/run_record.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/control/double_slit_problem.hpp"
#include "implicit/control/path_integral.hpp"

namespace implicit::experiments {

/// What estimates the control in a run.
enum class SlitImplementation {
  kGeneric,    ///< control::estimate_control on double_slit_problem
  kWallSpace,  ///< DoubleSlit::estimate_control, which samples the wall offset alone
};

/// The generic estimator's options for one of Table 2's estimators (spec §2.4.4-2.4.5): W2 with
/// the frozen wall is ModeSampling::kEachMode with freeze_walls, plain FD the same without, and
/// the paper's P is kDominant with Laplace weights; h = 1e-3 whatever x.
control::EstimatorOptions slit_estimator_options(control::SlitEstimator estimator, int samples);

/// One closed-loop run (spec §2.4.6) with the generic estimator: the noise and the exact
/// trajectory as control::simulate_slit_run, the estimated one by control::simulate_closed_loop.
control::SlitRun generic_slit_run(const control::DoubleSlit& slit,
                                  const control::DoubleSlitProblem& problem,
                                  const control::EstimatorOptions& options, std::uint64_t seed,
                                  std::uint64_t run);

/// The table's settings. Run r uses only streams keyed by (seed, r, ...), so the table is
/// bit-identical for any thread count.
struct SlitTableOptions {
  int samples = 50;
  int runs = 500;
  control::SlitEstimator estimator = control::SlitEstimator::kFrozenWall;
  std::uint64_t seed = 1;
  SlitImplementation implementation = SlitImplementation::kGeneric;
  control::SlitSampling sampling = control::SlitSampling::kWall;  ///< of kWallSpace
};

/// One run of the table (a named record: it travels between ranks, run_record.hpp).
struct SlitTableRow {
  double error_x = 0.0, error_u = 0.0;  ///< relative errors (fractions, not %)
  bool crashed_exact = false, crashed_estimate = false;
  int fallbacks = 0;
  double ess_mean = 0.0;
  static constexpr auto fields() {
    using R = SlitTableRow;
    using F = RecordField<R>;
    return std::array{F{"error_x", &R::error_x},
                      F{"error_u", &R::error_u},
                      F{"crashed_exact", &R::crashed_exact},
                      F{"crashed_estimate", &R::crashed_estimate},
                      F{"fallbacks", &R::fallbacks},
                      F{"ess_mean", &R::ess_mean}};
  }
};

struct SlitTable {
  std::vector<SlitTableRow> runs;
  double error_x_mean = 0.0, error_x_std = 0.0, error_x_median = 0.0;  ///< fractions
  double error_u_mean = 0.0, error_u_std = 0.0, error_u_median = 0.0;  ///< fractions
  /// Runs whose estimated-control trajectory crashed. Paper mode: about 0.45 (0.460 at M = 10,
  /// 0.447 at M = 50, 0.434 at M = 500, from 20 000 runs; P aims at a slit edge, so the last step
  /// misses with probability 1/2). A 500-run table has a binomial SE of 0.022; the spec's "0.49"
  /// is such an estimate (tests/apps/slit_table_slow.cpp, PaperModeCrashFraction).
  double crash_fraction = 0.0;
  /// Runs whose exact-control trajectory crashed: 0.235 (a discrete-time effect: the
  /// continuous-time optimal control never crashes).
  double exact_crash_fraction = 0.0;
  int fallbacks = 0;  ///< control evaluations where no sample passed
  double ess_mean = 0.0;
};

/// Runs options.runs closed-loop runs in parallel over runs (parallel_for, one process).
SlitTable run_slit_table(const control::DoubleSlit& slit, const SlitTableOptions& options);

/// Run `run` with the table's settings: its trajectories (Figure 2) and its row.
control::SlitRun slit_run(const control::DoubleSlit& slit, const SlitTableOptions& options,
                          std::uint64_t run);

/// Run `run` of run_slit_table alone (its row depends on nothing else), and the table from its
/// rows in run order: run_slit_table is summarise_slit_table of every slit_table_row. For callers
/// that spread the runs further (parallel_runs.hpp).
SlitTableRow slit_table_row(const control::DoubleSlit& slit, const SlitTableOptions& options,
                            std::uint64_t run);
SlitTable summarise_slit_table(std::vector<SlitTableRow> rows);

}  // namespace implicit::experiments
