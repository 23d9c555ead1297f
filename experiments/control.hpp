#pragma once
// The paper's path integral control experiments (§3): the double slit (Table 2, Figures 1-2),
// the robot arm (Figure 4) and Himmelblau's function (Table 4, Figure 5).
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

#include "experiments/choices.hpp"
#include "experiments/run_context.hpp"
#include "experiments/run_record.hpp"

namespace implicit::experiments {

// ---- Path integral control (paper §3) -------------------------------------------------------
struct SlitSettings {
  int samples = 50;  ///< M, samples per psi estimate
  int runs = 500;    ///< closed-loop runs (Table 2)
  /// "paper" (estimator P), "corrected" (W2, frozen wall) or "plain" (parse_slit_mode)
  control::SlitEstimator mode = control::SlitEstimator::kFrozenWall;
  /// "generic" (the library's path integral estimator on the double slit as a ControlProblem) or
  /// "wall-space" (DoubleSlit's own estimator, one scalar per sample: the same table to
  /// rounding, faster)
  SlitImplementation estimator = SlitImplementation::kGeneric;  ///< parse_slit_estimator
  int naive_mc_small = 5000;  ///< plain Monte Carlo paths (Figure 1)
  int naive_mc_large = 100000;
};
/// Keys: samples, runs, mode, estimator, error_x_mean/std/median, error_u_mean/std/median (in %),
/// crash_fraction, naive_mc_samples, naive_mc_passed, seconds. CSV: figure1_*.csv, figure2_*.csv.
nlohmann::json run_slit(const SlitSettings& s, const RunContext& ctx);

struct ArmSettings {
  /// "generic" (the library's estimator on each joint as a ControlProblem with partial noise) or
  /// "closed-form" (joint_path_integral, O(n) per joint: the same controls to 1e-7, 100 times
  /// faster). The semi-implicit check always uses the closed form, which alone has that scheme.
  control::ArmController estimator = control::ArmController::kGeneric;  ///< parse_arm_estimator
};
/// Keys: estimator, lqr_max_abs_diff, lqr_max_abs_diff_semi_implicit,
/// final_angle_error_exact_rad, final_angle_error_wrong_model_rad, seconds, ...
/// CSV: figure4_arm.csv.
nlohmann::json run_arm(const ArmSettings& s, const RunContext& ctx);

struct HimmelblauSettings {
  int runs = 70;
  int samples = 50;
};
/// One closed-loop run of run_himmelblau, as it travels between ranks (control::HimmelblauRun).
struct HimmelblauRunRecord {
  double cost = 0.0, final_f = 0.0, ess_mean = 0.0;
  int failed_minimizations = 0;
  double last_noise_1 = 0.0, last_noise_2 = 0.0;  ///< W_{K-1}
  double max_laplace_gap = 0.0;
  std::vector<double> x, u;  ///< the states and the controls, two numbers each
  static constexpr auto fields() {
    using R = HimmelblauRunRecord;
    using F = RecordField<R>;
    return std::array{F{"cost", &R::cost},
                      F{"final_f", &R::final_f},
                      F{"ess_mean", &R::ess_mean},
                      F{"failed_minimizations", &R::failed_minimizations},
                      F{"last_noise_1", &R::last_noise_1},
                      F{"last_noise_2", &R::last_noise_2},
                      F{"max_laplace_gap", &R::max_laplace_gap},
                      F{"x", &R::x},
                      F{"u", &R::u}};
  }
};

/// Keys: runs, samples, runs_below_10, mean_cost, mean_final_f, newton_final_f, seconds.
/// CSV: table4_himmelblau.csv, figure5_*.csv.
nlohmann::json run_himmelblau(const HimmelblauSettings& s, const RunContext& ctx);

}  // namespace implicit::experiments
