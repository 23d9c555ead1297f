#pragma once
// When the implicit proposal pays (beyond the paper): implicit against bootstrap MCL on simulated
// logs over the ratio of process to sensor noise and over the step length.
// Each experiment takes its settings and a RunContext, writes its CSV files into ctx.out_dir (when
// set) and returns one JSON object with the keys documented in docs/cli.md; the runs are spread
// over threads and MPI ranks (parallel_runs.hpp), each run's result a named record
// (run_record.hpp). The subcommands (apps/cmd_*.cpp), `implicit reproduce` and the Python module
// all call these.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/run_context.hpp"
#include "experiments/run_record.hpp"

namespace implicit::experiments {

// ---- When the implicit proposal pays (beyond the paper) -------------------------------------
struct ProposalGainSettings {
  int particles = 100;
  int runs = 20;                                          ///< simulated logs per point
  double duration = 48.0;                                 ///< [s] simulated per log
  double ratio_dt = 0.1;                                  ///< [s] step length of the ratio sweep
  std::vector<double> ratios = {0.1, 0.3, 1, 3, 10};      ///< process sd per step / range sd
  std::vector<double> dts = {0.02, 0.05, 0.1, 0.2, 0.4};  ///< [s] step lengths of the dt sweep
  double dt_range_sd = 0.02;                              ///< [m] range sd of the dt sweep
};
/// One simulated log of run_proposal_gain, both proposals on it.
struct ProposalGainRunRecord {
  double implicit_ess = 0.0, implicit_rmse_m = 0.0, implicit_cpu_ms_per_step = 0.0;
  double standard_ess = 0.0, standard_rmse_m = 0.0, standard_cpu_ms_per_step = 0.0;
  static constexpr auto fields() {
    using R = ProposalGainRunRecord;
    using F = RecordField<R>;
    return std::array{F{"implicit_ess", &R::implicit_ess},
                      F{"implicit_rmse_m", &R::implicit_rmse_m},
                      F{"implicit_cpu_ms_per_step", &R::implicit_cpu_ms_per_step},
                      F{"standard_ess", &R::standard_ess},
                      F{"standard_rmse_m", &R::standard_rmse_m},
                      F{"standard_cpu_ms_per_step", &R::standard_cpu_ms_per_step}};
  }
};

/// Keys: particles, runs, duration_s, scan_period_s, seed, threads, points (each: sweep, dt,
/// range_sd, bearing_sd, ratio, implicit/standard/diff with ess, rmse_m, cpu_ms_per_step and
/// their _se), carpark_ratio {A, B}, seconds. CSV: proposal_gain.csv.
nlohmann::json run_proposal_gain(const ProposalGainSettings& s, const RunContext& ctx);

}  // namespace implicit::experiments
