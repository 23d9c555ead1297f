#pragma once
// The paper's experiments as functions: each takes its settings and a RunContext, writes its CSV
// files into ctx.out_dir (when set) and returns one JSON object with the keys documented in
// docs/cli.md. The subcommands (apps/cmd_*.cpp) and `implicit reproduce` both call these.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "context.hpp"
#include "implicit/robot/landmark_observation.hpp"
#include "run_record.hpp"

namespace implicit::app {

// ---- Path integral control (paper §3) -------------------------------------------------------
struct SlitSettings {
  int samples = 50;                ///< M, samples per psi estimate
  int runs = 500;                  ///< closed-loop runs (Table 2)
  std::string mode = "corrected";  ///< "paper" (estimator P) or "corrected" (W2, frozen wall)
  /// "generic" (the library's path integral estimator on the double slit as a ControlProblem) or
  /// "wall-space" (DoubleSlit's own estimator, one scalar per sample: the same table to
  /// rounding, faster)
  std::string estimator = "generic";
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
  std::string estimator = "generic";
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

// ---- Monte Carlo localization (paper §4.1) --------------------------------------------------
struct MclSettings {
  std::string method = "implicit";  ///< "standard" (bootstrap) or "implicit"
  int particles = 100;
  int runs = 20;
  std::string data_dir;        ///< empty: the bundled Car Park data
  std::string config = "A";    ///< noise setting: "A" (P = 0.5) or "B" (P = 0.1)
  double p = -1.0;             ///< override P (both diagonal entries); < 0: from config
  double q = -1.0;             ///< override Q position entries q1 = q2 [m]; < 0: 0.1
  std::string map = "linear";  ///< implicit proposal: "linear" or "random" map
  bool clutter = true;         ///< dropped detections contribute the clutter density p0
  /// Labelled detections: chi-square gate on d^2 against the prediction; 0 = trust every label.
  double label_gate = robot::kLabelGateDefault;
  std::string sigma2 = "variance";  ///< reading of Table 7's Sigma2: "variance" or "std"
  std::string trajectory;           ///< TUM file of run 0's estimate (empty: none)
  std::string truth_trajectory;     ///< TUM file of the truth the runs are scored against
  std::string truth = "gps";        ///< ground truth: "gps" or "reference" (GPS-aided MCL run)
  double gps_std = 0.5;             ///< [m] GPS std assumed by the reference run
  int reference_particles = 5000;   ///< particles of the reference run
  std::string model;                ///< "ute" | "unicycle"; empty: what the log declares
  std::vector<double> control_sd;   ///< motion noise sd of u1, u2 (overrides p); empty: default
  std::vector<double> state_sd;     ///< motion noise sd of x, y, heading; empty: default
  double range_sd = 0.0;            ///< sensor range sd [m]; 0: Table 7 per --sigma2
  double bearing_sd_deg = 0.0;      ///< sensor bearing sd [deg]; 0: Table 7 per --sigma2
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

// ---- SLAM (paper §4.2) ----------------------------------------------------------------------
struct SlamSettings {
  std::string method = "implicit";  ///< ekf | fastslam1 | fastslam2 | implicit | implicit-rb
  int particles = 100;
  int datasets = 50;
  std::string data_dir;                  ///< empty: synthetic Car Park data; else a plain-text log
  std::string association = "known";     ///< "ml" or "known"
  std::string truth = "paper";           ///< "paper" (noise-free) or "consistent"
  int laser_every = 1;                   ///< laser update every k-th motion step
  double consistent_noise_scale = 0.01;  ///< Sigma1 factor of truth and filters in "consistent"
  int dense_landmarks = 0;               ///< > 0: a dense field of this many landmarks (scaling)
  int dense_laps = 1;                    ///< route length of the dense field, in Car Park laps
  double min_range = 0.0;                ///< detections closer than this are ignored [m]
  double control_noise = 0.5;            ///< P = diag(p, p) of the filters' motion model
  // The filters' laser model and association; 0 keeps the spec's values (Sigma2 of §3.2, the
  // chi^2_2 99 % gate 9.21, p0 = 1/(15 pi)). The synthetic data always use the spec's Sigma2.
  double range_sd = 0.0;              ///< sd of the range noise [m]
  double bearing_sd_deg = 0.0;        ///< sd of the bearing noise [deg]
  double gate_chi2 = 0.0;             ///< ML gate on d^2
  double new_landmark_density = 0.0;  ///< p0 [1/(m rad)]
  std::string model;                  ///< "ute" | "unicycle"; empty: what the log declares
  std::vector<double> control_sd;     ///< motion noise sd of u1, u2 (overrides control_noise)
  std::vector<double> state_sd;       ///< motion noise sd of x, y, heading; empty: default
  std::string trajectory;             ///< TUM file of run 0's path (empty: none)
  std::string truth_trajectory;       ///< TUM file of data set 0's truth, where known
};
/// One data set's run of run_slam: its metrics and the filter's statistics; the path and map only
/// for run 0 (the CSV files), the NEES per step only with the consistent truth (the band).
struct SlamRunRecord {
  double error_percent = 0.0, error_aligned_percent = 0.0;
  double rmse_pose_m = 0.0, rmse_pose_aligned_m = 0.0, rmse_heading_rad = 0.0;
  double rmse_map_m = 0.0, map_shape_m = 0.0, nees_mean = 0.0;
  std::size_t landmarks = 0;
  double ess_fraction_sum = 0.0;
  std::size_t weighted_steps = 0, resamplings = 0, newton_iterations = 0, newton_solves = 0;
  std::size_t skipped = 0;  ///< detections below min_range
  std::size_t map_bytes = 0;
  double wall_seconds = 0.0;
  std::size_t steps = 0, scored_steps = 0;
  std::string name;          ///< the data set's
  std::vector<double> nees;  ///< per step
  std::vector<double> path;  ///< x, y, heading per pose
  std::vector<double> map;   ///< id, x, y per landmark
  static constexpr auto fields() {
    using R = SlamRunRecord;
    using F = RecordField<R>;
    return std::array{F{"error_percent", &R::error_percent},
                      F{"error_aligned_percent", &R::error_aligned_percent},
                      F{"rmse_pose_m", &R::rmse_pose_m},
                      F{"rmse_pose_aligned_m", &R::rmse_pose_aligned_m},
                      F{"rmse_heading_rad", &R::rmse_heading_rad},
                      F{"rmse_map_m", &R::rmse_map_m},
                      F{"map_shape_m", &R::map_shape_m},
                      F{"nees_mean", &R::nees_mean},
                      F{"landmarks", &R::landmarks},
                      F{"ess_fraction_sum", &R::ess_fraction_sum},
                      F{"weighted_steps", &R::weighted_steps},
                      F{"resamplings", &R::resamplings},
                      F{"newton_iterations", &R::newton_iterations},
                      F{"newton_solves", &R::newton_solves},
                      F{"skipped", &R::skipped},
                      F{"map_bytes", &R::map_bytes},
                      F{"wall_seconds", &R::wall_seconds},
                      F{"steps", &R::steps},
                      F{"scored_steps", &R::scored_steps},
                      F{"name", &R::name},
                      F{"nees", &R::nees},
                      F{"path", &R::path},
                      F{"map", &R::map}};
  }
};

/// Keys: method, particles, datasets, error_percent_mean/std, error_aligned_percent_mean,
/// map_shape_m, ess_mean, resamplings, rmse_pose_m, rmse_pose_aligned_m, rmse_map_m, nees_mean
/// (consistent mode), cpu_ms_per_step, peak_memory_mb, seconds. CSV:
/// slam_<method>_M<particles>_{path,map}.csv.
nlohmann::json run_slam(const SlamSettings& s, const RunContext& ctx);

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

}  // namespace implicit::app
