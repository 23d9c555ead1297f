#pragma once
// Landmark SLAM, the paper's §4.2: EKF, FastSLAM 1.0/2.0 and implicit SLAM on synthetic Car Park
// data or plain-text logs (Table 6, Figure 7).
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
#include "implicit/robot/pose_graph.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::experiments {

// ---- SLAM (paper §4.2) ----------------------------------------------------------------------
struct SlamSettings {
  std::string method = "implicit";  ///< ekf | fastslam1 | fastslam2 | implicit | implicit-rb
  int particles = 100;
  int datasets = 50;
  std::string data_dir;               ///< empty: synthetic Car Park data; else a plain-text log
  std::string association = "known";  ///< "ml" or "known"
  slam::TruthMode truth = slam::TruthMode::kPaper;  ///< "paper" (noise-free) or "consistent"
  int laser_every = 1;                              ///< laser update every k-th motion step
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
  std::string model;  ///< a motion model by name (motion_models.hpp); empty: what the log declares
  std::vector<double> control_sd;  ///< motion noise sd of u1, u2 (overrides control_noise)
  std::vector<double> state_sd;    ///< motion noise sd of x, y, heading; empty: default
  std::string trajectory;          ///< TUM file of run 0's path (empty: none)
  std::string truth_trajectory;    ///< TUM file of data set 0's truth, where known
  std::string g2o;                 ///< g2o file of run 0's pose graph and map (empty: none)
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
/// slam_<method>_M<particles>_{path,map}.csv. With s.g2o also g2o_point_edges and
/// g2o_detections_unassociated (slam_pose_graph).
nlohmann::json run_slam(const SlamSettings& s, const RunContext& ctx);

/// The g2o graph of a run (the --g2o file): its path as the poses; per step n an edge n-1 -> n
/// whose measurement is the increment the filter's motion model predicts from the estimate at
/// n-1 with u_n, and whose information is that model's process noise (additive in the world
/// frame) seen from pose n-1 (robot::world_noise_edge_information); the final map as landmarks;
/// and each detection the filter used (range >= min_range) as a point edge from pose n, with the
/// filter's sensor covariance (robot::range_bearing_point_edge). The detection's landmark: known
/// association, the map's landmark of its id; ML, which keeps no record of its choices, the
/// landmark nearest the detection in the metric of the sensor covariance at the estimated pose,
/// within options.gate_chi2 (the others are left out and counted).
struct SlamPoseGraph {
  robot::PoseGraph2 graph;
  std::size_t unassociated = 0;  ///< detections without a landmark: no point edge
};
SlamPoseGraph slam_pose_graph(const slam::SlamDataset& d, const slam::SlamRun& run,
                              const slam::SlamOptions& options);

}  // namespace implicit::experiments
