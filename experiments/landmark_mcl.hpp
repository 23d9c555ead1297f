#pragma once
// Monte Carlo localization on beacon (landmark) data, the paper's §4.1: standard and implicit
// MCL on the Car Park data or a robot log (Table 5, Figure 6), global starts and kidnapping
// (spec §3.11).
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
#include "implicit/robot/landmark_observation.hpp"

namespace implicit::experiments {

// ---- Monte Carlo localization (paper §4.1) --------------------------------------------------
struct MclSettings {
  std::string method = "implicit";  ///< "standard" (bootstrap) or "implicit"
  int particles = 100;
  int runs = 20;
  std::string data_dir;                  ///< empty: the bundled Car Park data
  NoiseConfig config = NoiseConfig::kA;  ///< "A" (P = 0.5) or "B" (P = 0.1)
  double p = -1.0;                       ///< override P (both diagonal entries); < 0: from config
  double q = -1.0;                       ///< override Q position entries q1 = q2 [m]; < 0: 0.1
  filter::ImplicitMap map = filter::ImplicitMap::kLinear;  ///< the implicit proposal's map
  bool clutter = true;  ///< dropped detections contribute the clutter density p0
  /// Labelled detections: chi-square gate on d^2 against the prediction; 0 = trust every label.
  double label_gate = robot::kLabelGateDefault;
  Sigma2Reading sigma2 = Sigma2Reading::kVariance;  ///< reading of Table 7's Sigma2
  std::string trajectory;                           ///< TUM file of run 0's estimate (empty: none)
  std::string truth_trajectory;     ///< TUM file of the truth the runs are scored against
  MclTruth truth = MclTruth::kGps;  ///< ground truth: GPS, or a GPS-aided MCL run
  double gps_std = 0.5;             ///< [m] GPS std assumed by the reference run
  int reference_particles = 5000;   ///< particles of the reference run
  std::string model;  ///< a motion model by name (motion_models.hpp); empty: what the log declares
  std::vector<double> control_sd;  ///< motion noise sd of u1, u2 (overrides p); empty: default
  std::vector<double> state_sd;    ///< motion noise sd of x, y, heading; empty: default
  double range_sd = 0.0;           ///< sensor range sd [m]; 0: Table 7 per --sigma2
  double bearing_sd_deg = 0.0;     ///< sensor bearing sd [deg]; 0: Table 7 per --sigma2
  // Global localization, kidnapping, recovery and KLD-sampling (spec §3.11).
  std::string init = "known";     ///< "known" (the log's initial pose) or "global"
  double start_span = 60.0;       ///< [s] global starts: run r starts r * span / runs in
  double duration = 0.0;          ///< [s] runs end at the first control + duration; 0: log's end
  double kidnap_at = -1.0;        ///< [s] after the first control; < 0: no kidnapping
  double kidnap_skip = 10.0;      ///< [s] of odometry and scans dropped at kidnap_at
  std::string recovery = "auto";  ///< none | uniform | mixture | auto (global/kidnap: by method)
  double recovery_alpha_slow = 0.001;
  double recovery_alpha_fast = 0.1;
  double kidnap_probability = 1e-3;
  bool kld = false;  ///< adaptive particle count
  double kld_err = 0.01;
  double kld_z = 0.99;
  int min_particles = 100;
  int max_particles = 5000;
  double cover_spacing = 2.0;  ///< [m] of the multi-start's grid
  int cover_headings = 8;
  /// --allow-empty: a global or kidnapping test that cannot happen (a kidnapping after the log's
  /// end, no ground truth to score) runs anyway and says so in the JSON ("empty") instead of
  /// being an error.
  bool allow_empty = false;
};
/// One run of run_mcl (known start).
struct MclRunRecord {
  double error_percent = 0.0, rmse_m = 0.0, heading_rmse_rad = 0.0, ess_fraction = 0.0;
  double cpu_ms_per_step = 0.0, wall_ms_per_step = 0.0;
  double detections_used = 0.0, detections_dropped = 0.0;  ///< per-particle means, summed
  double newton_evaluations = 0.0;                         ///< per particle and update
  double max_error_m = 0.0;
  int resamplings = 0;
  double min_log_likelihood_increment = 0.0;
  int fallbacks = 0, failures = 0;
  int labelled_gated = 0;  ///< labelled detections left out by the prediction gate
  static constexpr auto fields() {
    using R = MclRunRecord;
    using F = RecordField<R>;
    return std::array{F{"error_percent", &R::error_percent},
                      F{"rmse_m", &R::rmse_m},
                      F{"heading_rmse_rad", &R::heading_rmse_rad},
                      F{"ess_fraction", &R::ess_fraction},
                      F{"cpu_ms_per_step", &R::cpu_ms_per_step},
                      F{"wall_ms_per_step", &R::wall_ms_per_step},
                      F{"detections_used", &R::detections_used},
                      F{"detections_dropped", &R::detections_dropped},
                      F{"newton_evaluations", &R::newton_evaluations},
                      F{"max_error_m", &R::max_error_m},
                      F{"resamplings", &R::resamplings},
                      F{"min_log_likelihood_increment", &R::min_log_likelihood_increment},
                      F{"fallbacks", &R::fallbacks},
                      F{"failures", &R::failures},
                      F{"labelled_gated", &R::labelled_gated}};
  }
};

/// One run of a global start or a kidnapping (run_mcl with --init global or --kidnap-at).
struct MclGlobalRunRecord {
  bool success = false;
  double time_to_converge_s = 0.0;  ///< NaN: never converged
  double rmse_after_settle_m = 0.0;
  double particles_mean = 0.0, particles_peak = 0.0;
  int injected = 0;  ///< particles drawn by recovery
  double cpu_ms_per_step = 0.0;
  double start_s = 0.0;  ///< from the log's first control
  bool uniform_start = false;
  static constexpr auto fields() {
    using R = MclGlobalRunRecord;
    using F = RecordField<R>;
    return std::array{F{"success", &R::success},
                      F{"time_to_converge_s", &R::time_to_converge_s},
                      F{"rmse_after_settle_m", &R::rmse_after_settle_m},
                      F{"particles_mean", &R::particles_mean},
                      F{"particles_peak", &R::particles_peak},
                      F{"injected", &R::injected},
                      F{"cpu_ms_per_step", &R::cpu_ms_per_step},
                      F{"start_s", &R::start_s},
                      F{"uniform_start", &R::uniform_start}};
  }
};

/// Keys: method, particles, runs, config, error_percent_mean/std/median, rmse_m,
/// heading_rmse_rad, ess_mean, cpu_ms_per_step, detections_used, detections_dropped, lost_runs,
/// seconds. CSV: mcl_<method>_M<particles>_trajectory.csv.
nlohmann::json run_mcl(const MclSettings& s, const RunContext& ctx);

}  // namespace implicit::experiments
