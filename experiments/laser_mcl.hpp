#pragma once
// Laser Monte Carlo localization on a recorded laser log by the semi-synthetic protocol
// (docs/specification.md, "Laser localization on recorded logs"):
//
//  1. the map is built from the log's reference poses and its real scans (or read from --map);
//  2. updates are taken where the reference pose moved update_min_d or turned update_min_a since
//     the last one (nav2's rule);
//  3. odometry between updates is synthesised from the reference increments with the alpha noise
//     of the odometry model, per run from the run's seed;
//  4. the filter sees the scans, the map and the odometry, never the reference poses; its estimate
//     is scored against them (position and heading RMSE, lost runs, ESS, particles, CPU).
//
// A robot log (log_format.hpp) with `laser` and `odometry` records is run on its recorded odometry
// instead (updates picked on it), its map, and its truth records as the reference (updates
// without truth are not scored; without any, the metrics are NaN).
//
//   LaserMclSettings s;
//   s.data = "data/carmen/intel-corrected.log.gz";
//   s.proposal = ProposalKind::kImplicit;
//   s.particles = 100;
//   LaserMclResult r = run_laser_mcl(s);
//   fmt::print("{}\n", to_json(r).dump());

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "implicit/filter/kld.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/filter/recovery.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/beam_model.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/odometry_model.hpp"

namespace implicit::experiments {

/// The proposal of a particle filter. Parsed from text in one place (parse_proposal).
enum class ProposalKind { kBootstrap, kImplicit };
std::string_view to_string(ProposalKind p);
/// "bootstrap" (or its old name "standard") or "implicit"; InvalidArgument otherwise.
ProposalKind parse_proposal(std::string_view text);

/// How a run starts: at the reference pose with a small spread, or anywhere on the map.
enum class StartKind { kKnown, kGlobal };
std::string_view to_string(StartKind s);
StartKind parse_start(std::string_view text);

/// The laser's observation model: the likelihood field (a distance field; differentiable, both
/// proposals) or the beam model (ray casting; the bootstrap proposal only).
enum class LaserModelKind { kLikelihoodField, kBeam };
std::string_view to_string(LaserModelKind m);
/// "likelihood-field" or "beam"; InvalidArgument otherwise.
LaserModelKind parse_laser_model(std::string_view text);

/// The pose a run reports at each update: the weighted mean of all particles, or the weighted
/// mean of the heaviest cluster (filter/pose_clusters.hpp; what AMCL reports), which stays on one
/// place while the posterior still has several.
enum class EstimateKind { kMean, kHeaviestCluster };
std::string_view to_string(EstimateKind e);
/// "mean" or "cluster"; InvalidArgument otherwise.
EstimateKind parse_estimate(std::string_view text);

/// Interpolation of the distance field, from text ("nearest", "bilinear", "bicubic").
robot::Interpolation parse_interpolation(std::string_view text);
std::string_view to_string(robot::Interpolation i);

/// A laser log prepared for localization: the updates, their reference poses and the map.
struct LaserDataset {
  std::string name;                     ///< the log's file name
  std::vector<robot::LaserScan> scans;  ///< at the update points
  std::vector<robot::Pose> reference;   ///< the robot's reference pose at each update
  robot::LaserMount mount;              ///< the laser on the robot (from the log)
  robot::OccupancyGrid map;
  std::size_t scans_in_log = 0;
  bool map_built = false;  ///< built from the reference poses (not read from a file)
  /// The robot's recorded odometry pose at each update (a robot log's `odometry` records,
  /// interpolated at the scan's time); empty when the log records none (CARMEN logs: the
  /// odometry is synthesised from the reference, per run). A robot log's reference is its truth,
  /// NaN at updates it does not cover (those are not scored).
  std::vector<robot::Pose> odometry;
  bool odometry_recorded() const { return !odometry.empty(); }
};

struct LaserDataOptions {
  /// A CARMEN log or a robot log (log_format.hpp) with `laser` and `odometry` records; plain or
  /// gzip, the format told from the content (robot::is_robot_log). Or a ROS bag (robot/bag.hpp),
  /// read as the CARMEN log it makes: its odometry is the reference.
  std::filesystem::path data;
  robot::BagOptions bag;  ///< a ROS bag's topics and frames
  /// A map_server YAML; empty: a robot log's `map` record, or built from a CARMEN log's reference
  /// poses.
  std::filesystem::path map;
  double map_resolution = 0.05;  ///< [m] of the built map
  double map_max_range = 40.0;   ///< [m] beams longer than this only clear space in the built map
  int map_min_echoes = 2;        ///< the built map's robot::GridMappingOptions::min_echoes (0: off)
  double update_min_d = 0.25;    ///< [m] nav2's update_min_d
  double update_min_a = 0.2;     ///< [rad] nav2's update_min_a
  std::size_t max_updates = 0;   ///< 0: all
  void validate() const;
};

LaserDataset load_laser_dataset(const LaserDataOptions& options);

/// Odometry increments u_1..u_n between consecutive reference poses (u_k: from pose k-1 to
/// pose k), each perturbed by the alpha noise from the stream (seed, k, purpose::kData).
std::vector<Vec<3>> synthesise_odometry(const std::vector<robot::Pose>& reference,
                                        const robot::OdometryAlphas& alphas, std::uint64_t seed);
/// The filter's controls of one run, u_k from update k-1 to update k (u_0 = 0): the increments of
/// the recorded odometry (heading change wrapped) when the dataset has it, else
/// synthesise_odometry(reference, noise, seed).
std::vector<Vec<3>> run_odometry(const LaserDataset& d, const robot::OdometryAlphas& noise,
                                 std::uint64_t seed);

struct LaserMclSettings {
  LaserDataOptions data;
  ProposalKind proposal = ProposalKind::kImplicit;
  filter::ImplicitMap implicit_map = filter::ImplicitMap::kLinear;
  int implicit_starts = 2;  ///< Newton starts per particle (ImplicitProposal::starts)
  /// Iterations a further start runs before it must be below the best minimum
  /// (ImplicitProposal::start_probe; 0: every start runs to convergence).
  int implicit_start_probe = 0;
  /// Share of implicit samples drawn from the motion prior (ImplicitProposal::defensive).
  double implicit_defensive = 0.0;
  std::size_t particles = 100;
  int runs = 10;
  std::uint64_t seed = 1;
  /// The synthesised odometry's noise, and the filter's motion model (the same by default).
  robot::OdometryAlphas odometry_noise{0.02, 0.02, 0.02, 0.02};
  robot::OdometryAlphas filter_alphas{0.02, 0.02, 0.02, 0.02};
  LaserModelKind laser_model = LaserModelKind::kLikelihoodField;
  robot::LikelihoodFieldParams laser;  ///< the likelihood field's parameters
  robot::BeamModelParams beam;         ///< the beam model's parameters
  filter::KldOptions kld;              ///< adaptive particle count (AMCL's bounds)
  /// Injection of particles drawn uniformly over free space when the filter looks lost (AMCL's
  /// recovery_alpha_slow / recovery_alpha_fast).
  filter::RecoveryOptions recovery;
  double resample_threshold = 0.5;
  StartKind start = StartKind::kKnown;
  double initial_std_xy = 0.1;        ///< [m] a known start's spread
  double initial_std_heading = 0.05;  ///< [rad]
  double lost_threshold = 1.0;        ///< [m] a run whose final error exceeds this is lost
  /// A global start counts as a success when the position error is below this [m] (and the
  /// heading error below 0.3 rad) at update global_updates and stays so to the end.
  double global_success_radius = 0.5;
  int global_updates = 10;
  EstimateKind estimate = EstimateKind::kMean;
  bool keep_tracks = false;  ///< keep each run's estimates (for figures)
  void validate() const;
};

/// One run of the filter over the log.
struct LaserMclRun {
  std::uint64_t seed = 0;
  double position_rmse_m = 0.0;  ///< over all updates
  double heading_rmse_rad = 0.0;
  double final_error_m = 0.0;  ///< at the last scored update
  int scored_updates = 0;      ///< updates with a reference (truth); the metrics are NaN if 0
  bool lost = false;
  bool global_success = false;   ///< global start only
  int updates_to_converge = -1;  ///< global start: first update from which the error stays small
  /// Global start: how well the first scan fits the reference and the best place the start
  /// found, log p(z | x) at the scan-matched pose nearest the reference (Newton from it, for a
  /// differentiable model; else at the reference) and the largest over the start's particles.
  /// A start whose best place fits better than the reference by several nats fails for want of
  /// evidence, not of particles. NaN where the log has no reference.
  double first_scan_fit_reference = std::numeric_limits<double>::quiet_NaN();
  double first_scan_fit_best = std::numeric_limits<double>::quiet_NaN();
  double ess_fraction_mean = 0.0;  ///< mean ESS / M at updates
  double particles_mean = 0.0;
  double cpu_us_per_update = 0.0;  ///< process CPU time per update [us]
  double newton_evaluations_mean = 0.0;
  int fallbacks = 0, failures = 0;
  std::vector<robot::Pose> estimates;  ///< per update (keep_tracks)
  std::vector<double> errors_m;        ///< per update (keep_tracks)
};

/// Mean and standard error of a per-run quantity.
struct MeanSe {
  double mean = 0.0, se = 0.0, median = 0.0;
};

struct LaserMclResult {
  LaserMclSettings settings;
  std::string data_name;
  std::size_t scans_in_log = 0, updates = 0;
  int map_width = 0, map_height = 0;
  double map_resolution = 0.0;
  bool map_built = false;
  bool odometry_recorded = false;  ///< the log's odometry (else synthesised)
  std::size_t scored_updates = 0;  ///< over all runs
  std::vector<LaserMclRun> runs;
  MeanSe position_rmse_m, heading_rmse_rad, cpu_us_per_update, ess_fraction;
  MeanSe particles;  ///< mean particle count over updates (varies under KLD-sampling)
  int lost_runs = 0;
  double global_success_rate = 0.0;  ///< global start only
  double seconds = 0.0;              ///< wall time of all runs
};

/// Called after each run with (runs done, runs in all).
using Progress = std::function<void(int, int)>;

/// Runs settings.runs filters (seeds seed, seed + 1, ...) on one prepared dataset.
LaserMclResult run_laser_mcl(const LaserMclSettings& settings, const LaserDataset& data,
                             const Progress& progress = {});
/// Loads the dataset, then runs.
LaserMclResult run_laser_mcl(const LaserMclSettings& settings, const Progress& progress = {});

/// The result by name (tracks left out unless include_tracks).
nlohmann::json to_json(const LaserMclResult& r, bool include_tracks = false);

}  // namespace implicit::experiments
