// Monte Carlo localization on the University Car Park data (paper §4.1, Table 5, Figure 6;
// spec §3.8-3.9): standard (bootstrap) and implicit MCL over several seeds.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "experiments/choices.hpp"
#include "experiments/landmark_mcl.hpp"
#include "experiments/landmark_mcl_global.hpp"
#include "experiments/motion_models.hpp"
#include "experiments/parallel_runs.hpp"
#include "experiments/run_statistics.hpp"
#include "experiments/tum_output.hpp"
#include "experiments/vehicle.hpp"
#include "experiments/wilson.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/carpark.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::experiments {
namespace {

using filter::LocalizationMetrics;
using filter::LocalizationProblem;
using filter::LocalizationRun;
using robot::Pose;

/// The data as a robot log: a Car Park folder (carpark_dr.csv inside) or a plain-text log file.
robot::RobotLog load_log(const std::string& data, const robot::UteModel& model) {
  const std::filesystem::path path =
      data.empty() ? robot::default_carpark_dir() : std::filesystem::path(data);
  if (std::filesystem::is_directory(path)) {
    require(std::filesystem::exists(robot::resolve_data_file(path / "carpark_dr.csv")),
            "mcl --data: expected a Car Park folder (with carpark_dr.csv) or a robot log file, got "
            "'{}'",
            path.string());
    return robot::carpark_to_log(robot::load_carpark(path), model);
  }
  require(std::filesystem::exists(path),
          "mcl --data: expected an existing folder or robot log file, got '{}'", path.string());
  return robot::read_robot_log(path);
}

/// A short stable hash (FNV-1a 64) naming the reference cache file by its inputs.
std::string fnv1a_hex(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

/// The GPS-aided reference track (paper §4.1's alternative ground truth): implicit MCL with the
/// paper's noise setting (config A, whatever the compared runs use, so every method and config is
/// scored against the same truth), the GPS fixes as extra position measurements, many particles
/// and a fixed seed. Cached as CSV in `cache_dir`, keyed by the data file's size and time stamp
/// and the reference settings (a stale or foreign file is recomputed, never trusted).
robot::TruthTrack load_or_make_reference(const LocalizationProblem& problem,
                                         const std::filesystem::path& data_file,
                                         const MclSettings& s, const std::filesystem::path& dir,
                                         std::string& cache_file, bool& from_cache) {
  const robot::UteModel model;  // config A: the paper's P = 0.5, Q = Table 7
  const robot::RangeBearingSensor sensor;
  filter::ReferenceOptions ro;
  ro.gps_std = s.gps_std;
  ro.particles = static_cast<std::size_t>(s.reference_particles);
  std::error_code ec;
  const auto size = std::filesystem::file_size(data_file, ec);
  const auto stamp = std::filesystem::last_write_time(data_file, ec).time_since_epoch().count();
  const std::string key = fmt::format(
      "implicit mcl reference v1; data {} ({} bytes, mtime {}); implicit linear config A; "
      "gps_std {}; particles {}; seed {}; steps {}",
      std::filesystem::absolute(data_file).string(), size, stamp, ro.gps_std, ro.particles, ro.seed,
      problem.schedule.steps.size());
  const std::filesystem::path file = dir / ("mcl_reference_truth_" + fnv1a_hex(key) + ".csv");
  cache_file = file.string();
  from_cache = false;
  {
    std::ifstream in(file);
    std::string line;
    if (in && std::getline(in, line) && line == "# " + key && std::getline(in, line)) {
      robot::TruthTrack t;
      while (std::getline(in, line)) {
        double x = 0, y = 0, h = 0;
        if (std::sscanf(line.c_str(), "%*d,%lf,%lf,%lf", &x, &y, &h) != 3) break;
        t.position.emplace_back(x, y);
        t.heading.push_back(h);
      }
      if (t.position.size() == problem.schedule.steps.size()) {
        from_cache = true;
        return t;
      }
    }
  }
  const robot::TruthTrack t =
      filter::reference_track(problem, model, sensor, filter::ImplicitProposal{}, ro);
  std::filesystem::create_directories(dir, ec);
  // Written under a temporary name and renamed: MPI ranks (or two runs) that make the same cache
  // at once each replace it whole, with the same content, and a reader never sees half a file.
  const bool temporary = dir == std::filesystem::temp_directory_path() / "implicit-cache";
  OutputFile cache(file, OutputFile::Mode::kReplace,
                   temporary ? "the reference cache in the system's temp folder" : "--out");
  std::ostream& out = cache.stream();
  out << "# " << key << "\nstep,x,y,heading\n";
  for (std::size_t n = 0; n < t.position.size(); ++n)
    out << fmt::format("{},{:.17g},{:.17g},{:.17g}\n", n + 1, t.position[n](0), t.position[n](1),
                       t.heading[n]);
  cache.commit();
  return t;
}

void write_trajectory(const std::filesystem::path& file, const LocalizationProblem& problem,
                      const LocalizationRun& run) {
  OutputFile output(file);
  std::ostream& out = output.stream();
  out << "step,time_s,truth_x,truth_y,truth_heading,est_x,est_y,est_heading,std_x,std_y,ess,"
         "resampled,updated,log_likelihood_increment\n";
  for (std::size_t n = 0; n < run.steps.size(); ++n) {
    const auto& s = run.steps[n];
    const Vec<2>& p = problem.truth.position[n];
    out << fmt::format(
        "{},{:.3f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.4f},{},{},{:.6f}\n",
        n + 1, problem.schedule.steps[n].time, p(0), p(1), problem.truth.heading[n], s.mean(0),
        s.mean(1), wrap_angle(s.mean(2)), std::sqrt(s.covariance(0, 0)),
        std::sqrt(s.covariance(1, 1)), s.ess, s.resampled ? 1 : 0, s.updated ? 1 : 0,
        s.log_likelihood_increment);
  }
  output.commit();
}

/// What run_mcl decided before the runs: the log, its name, and the JSON keys of the models.
struct MclSetup {
  robot::RobotLog log;
  std::string model_name;
  double p = 0.0;     ///< the Ute's control std (both entries), for the "p" key
  MotionNoise noise;  ///< the motion noise the filter used, defaults filled in
  std::chrono::steady_clock::time_point start;
};

robot::RangeBearingSensor mcl_sensor(const MclSettings& s) {
  const double sr = 0.05, sb = 0.05 * kPi / 180.0;  // Table 7's Sigma2 entries
  robot::RangeBearingSensor sensor = s.sigma2 == Sigma2Reading::kVariance
                                         ? robot::RangeBearingSensor(sr, sb)
                                         : robot::RangeBearingSensor::from_std(sr, sb);
  if (s.range_sd > 0 || s.bearing_sd_deg > 0) {
    const Mat<2>& n = sensor.noise_covariance();
    sensor = robot::RangeBearingSensor(
        s.range_sd > 0 ? s.range_sd * s.range_sd : n(0, 0),
        s.bearing_sd_deg > 0 ? std::pow(s.bearing_sd_deg * kPi / 180.0, 2) : n(1, 1));
  }
  return sensor;
}

template <typename Motion>
nlohmann::json run_mcl_model(const MclSettings& s, const RunContext& ctx, const Motion& model,
                             const robot::RangeBearingSensor& sensor, const MclSetup& setup);

}  // namespace

void write_mcl_tum_files(const MclSettings& s, const LocalizationProblem& problem,
                         const LocalizationRun& run) {
  if (!s.trajectory.empty()) {
    TumTrack est;
    for (std::size_t k = 0; k < run.steps.size(); ++k)
      est.add(problem.schedule.steps[run.first_step + k].time, run.steps[k].mean);
    est.write(s.trajectory, "mcl --trajectory");
  }
  if (!s.truth_trajectory.empty()) {
    TumTrack truth;
    const auto& t = problem.truth;
    for (std::size_t n = 0; n < problem.schedule.steps.size(); ++n)
      if (n < t.position.size() && n < t.heading.size())
        truth.add(problem.schedule.steps[n].time,
                  Pose(t.position[n](0), t.position[n](1), t.heading[n]));
    truth.write(s.truth_trajectory, "mcl --truth-trajectory");
  }
}

nlohmann::json run_mcl(const MclSettings& s, const RunContext& ctx) {
  (void)mcl_methods().check(s.method);
  require(s.particles >= 1, "mcl --particles: expected >= 1, got {}", s.particles);
  require(s.runs >= 1, "mcl --runs: expected >= 1, got {}", s.runs);
  require(s.gps_std > 0 && std::isfinite(s.gps_std), "mcl --gps-std: expected > 0, got {}",
          s.gps_std);
  require(s.reference_particles >= 1, "mcl --reference-particles: expected >= 1, got {}",
          s.reference_particles);
  // Checked before the data (and a reference track) are loaded: a refusal costs nothing.
  if (s.init != "known" || s.kidnap_at >= 0) {
    check_global_settings(s);
  } else {
    require(!s.kld && (s.recovery == "auto" || s.recovery == "none"),
            "mcl --kld / --recovery: expected --init global or --kidnap-at with them (they act "
            "only on global-start and kidnapping runs)");
  }
  MclSetup setup;
  setup.start = std::chrono::steady_clock::now();
  setup.log = load_log(s.data_dir, robot::UteModel());  // Car Park folders: the Ute's geometry
  const std::string data_name = s.data_dir.empty() ? "data/carpark" : s.data_dir;
  setup.model_name = resolve_model(
      "mcl", s.model, setup.log.vehicle ? std::optional(setup.log.vehicle->model) : std::nullopt,
      data_name);
  const bool assumed = !setup.log.vehicle;  // the Car Park folders declare the Ute
  const robot::RangeBearingSensor sensor = mcl_sensor(s);
  const MotionModelEntry& entry = motion_model(setup.model_name, "mcl --model");
  MotionNoise noise{s.control_sd, s.state_sd};
  if (entry.car_park_noise) {
    // Models (spec §3.1, §3.2, §3.9): config A is the paper's P = 0.5, config B P = 0.1; --p and
    // --q set P and Q's position entries, and --control-sd / --state-sd override both.
    const double p = s.p >= 0 ? s.p : (s.config == NoiseConfig::kA ? 0.5 : 0.1);
    if (noise.control_sd.empty()) noise.control_sd = {p, p};
    if (noise.state_sd.empty() && s.q >= 0)
      noise.state_sd = {s.q, s.q, entry.default_noise.state_sd.at(2)};
    setup.p = noise.control_sd[0];
  } else {
    require(s.truth == MclTruth::kGps,
            "mcl --truth reference: the GPS-aided reference run is the Car Park's (--model ute), "
            "got --model {}",
            setup.model_name);
  }
  const robot::VehicleDeclaration declared =
      full_declaration(entry, setup.log.vehicle ? *setup.log.vehicle : robot::VehicleDeclaration{});
  if (assumed) warn_vehicle_assumed("mcl", data_name, declared);
  setup.noise = noise_with_defaults(entry, noise);
  const robot::AnyMotionModel model = make_motion_model(entry, declared, setup.noise);
  nlohmann::json j = visit_motion_model(
      model, [&](const auto& motion) { return run_mcl_model(s, ctx, motion, sensor, setup); });
  j["model"] = setup.model_name;  // the global and kidnapping runs' JSON too
  j["vehicle_assumed"] = assumed;
  return j;
}

namespace {

/// The reference truth in place of the GPS (--truth reference), with where it came from.
struct ReferenceTruth {
  std::string cache;
  bool from_cache = false;
  double vs_gps = 0.0;  ///< RMS distance [m] between the reference track and the GPS
};

ReferenceTruth use_reference_truth(LocalizationProblem& problem, const MclSettings& s,
                                   const RunContext& ctx) {
  ReferenceTruth ref;
  const std::filesystem::path data =
      s.data_dir.empty() ? robot::default_carpark_dir() : std::filesystem::path(s.data_dir);
  const std::filesystem::path data_file = robot::resolve_data_file(
      std::filesystem::is_directory(data) ? data / "carpark_dr.csv" : data);
  // Cached next to the other outputs when --out is given, else in the system temp folder.
  const std::filesystem::path dir = ctx.out_dir.empty()
                                        ? std::filesystem::temp_directory_path() / "implicit-cache"
                                        : std::filesystem::path(ctx.out_dir);
  const robot::TruthTrack gps = problem.truth;
  problem.truth = load_or_make_reference(problem, data_file, s, dir, ref.cache, ref.from_cache);
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < gps.position.size(); ++k) {
    if (!gps.position[k].allFinite()) continue;
    sum += (gps.position[k] - problem.truth.position[k]).squaredNorm();
    ++n;
  }
  ref.vs_gps = n > 0 ? std::sqrt(sum / n) : 0.0;
  return ref;
}

/// The summaries over the runs that the JSON and the CSV files report.
struct MclSummary {
  std::vector<double> err, rmse, hrmse, ess, cpu, wall, used, dropped, newton, max_err, resamplings,
      min_loglik, gated;
  int lost = 0, fallbacks = 0, failures = 0;
};

MclSummary summarise(const std::vector<MclRunRecord>& records) {
  using R = MclRunRecord;
  MclSummary m;
  m.err = column(records, &R::error_percent);
  m.rmse = column(records, &R::rmse_m);
  m.ess = column(records, &R::ess_fraction);
  m.cpu = column(records, &R::cpu_ms_per_step);
  m.wall = column(records, &R::wall_ms_per_step);
  m.used = column(records, &R::detections_used);
  m.dropped = column(records, &R::detections_dropped);
  m.newton = column(records, &R::newton_evaluations);
  m.max_err = column(records, &R::max_error_m);
  m.resamplings = column(records, &R::resamplings);
  m.min_loglik = column(records, &R::min_log_likelihood_increment);
  m.gated = column(records, &R::labelled_gated);
  for (const R& r : records) {
    // The heading RMSE only of the runs that have one (truth with headings).
    if (std::isfinite(r.heading_rmse_rad)) m.hrmse.push_back(r.heading_rmse_rad);
    m.lost += r.max_error_m > 5.0 ? 1 : 0;
    m.fallbacks += r.fallbacks;
    m.failures += r.failures;
  }
  return m;
}

MclRunRecord record_of(const LocalizationRun& run, const LocalizationMetrics& m) {
  const auto steps = static_cast<double>(run.steps.size());
  MclRunRecord rec;
  rec.error_percent = m.error_percent;
  rec.rmse_m = m.rmse;
  rec.heading_rmse_rad = m.heading_rmse;
  rec.ess_fraction = m.ess_fraction;
  rec.cpu_ms_per_step = 1e3 * run.cpu_seconds / steps;
  rec.wall_ms_per_step = 1e3 * run.seconds / steps;
  rec.detections_used = m.detections_used;
  rec.detections_dropped = m.detections_dropped;
  rec.newton_evaluations = m.newton_evaluations;
  rec.max_error_m = m.max_error;
  rec.resamplings = run.resamplings;
  rec.min_log_likelihood_increment = m.min_log_likelihood_increment;
  rec.fallbacks = m.fallbacks;
  rec.failures = m.failures;
  rec.labelled_gated = m.gated;
  return rec;
}

/// The settings the records depend on (parallel_runs.hpp: the key of --resume).
std::string runs_key(const MclSettings& s, const RunContext& ctx, const MclSetup& setup) {
  return fmt::format(
      "seed={} method={} M={} config={} p={:a} q={:a} map={} clutter={} sigma2={} truth={} "
      "gps_std={:a} reference_M={} data={} model={} control_sd={:a} state_sd={:a} label_gate={:a} "
      "range_sd={:a} "
      "bearing_sd={:a}",
      ctx.seed, s.method, s.particles, name_of(s.config), setup.p, s.q, name_of(s.map), s.clutter,
      name_of(s.sigma2), name_of(s.truth), s.gps_std, s.reference_particles, s.data_dir,
      setup.model_name, fmt::join(s.control_sd, ","), fmt::join(s.state_sd, ","), s.label_gate,
      s.range_sd, s.bearing_sd_deg);
}

/// The beacon extraction and the sensor model against the survey: every detection placed in the
/// world with the ground-truth pose, and its distance to the nearest surveyed beacon (spec §3.8).
std::vector<robot::DetectionResidual> detection_check(const robot::RobotLog& log,
                                                      const LocalizationProblem& problem) {
  const std::size_t steps = problem.schedule.steps.size();
  if (problem.truth.position.size() != steps || problem.truth.heading.size() != steps) return {};
  std::vector<Pose> truth_poses(steps);
  for (std::size_t n = 0; n < steps; ++n)
    truth_poses[n] << problem.truth.position[n], problem.truth.heading[n];
  return robot::detection_residuals(log, problem.schedule, truth_poses);
}

/// The means and spreads over the runs, by the keys of docs/cli.md.
void add_summary_json(nlohmann::json& j, const MclSummary& m) {
  j["error_percent_mean"] = mean_of(m.err);
  j["error_percent_std"] = sd_of(m.err);
  j["error_percent_median"] = median_of(m.err);
  j["error_percent_runs"] = m.err;
  j["rmse_m"] = mean_of(m.rmse);
  // The name every mcl and slam output shares (docs/cli.md, "Names shared by mcl and slam").
  j["position_rmse_m"] = mean_of(m.rmse);
  j["rmse_m_std"] = sd_of(m.rmse);
  j["rmse_m_median"] = median_of(m.rmse);
  j["max_error_m_median"] = median_of(m.max_err);
  j["heading_rmse_rad"] = mean_of(m.hrmse);
  j["ess_mean"] = mean_of(m.ess);
  j["ess_std"] = sd_of(m.ess);
  j["resamplings_mean"] = mean_of(m.resamplings);
  j["cpu_ms_per_step"] = mean_of(m.cpu);
  j["cpu_ms_per_step_std"] = sd_of(m.cpu);
  j["cpu_ms_per_step_median"] = median_of(m.cpu);
  j["wall_ms_per_step"] = mean_of(m.wall);
  j["newton_evaluations_per_update"] = mean_of(m.newton);
  j["min_log_likelihood_increment_median"] = median_of(m.min_loglik);
}

/// The data and what the runs made of it, by the keys of docs/cli.md.
void add_data_json(nlohmann::json& j, const MclSettings& s, const MclSummary& m,
                   const LocalizationProblem& problem) {
  j["detections_total"] = problem.detections_total;
  j["detections_used"] = mean_of(m.used);
  j["detections_dropped"] = mean_of(m.dropped);
  j["label_gate"] = s.label_gate;
  j["labelled_gated"] = mean_of(m.gated);  // per run: labelled detections left out by the gate
  j["scans_with_detections"] = problem.schedule.scans_with_observations;
  j["scans_skipped"] = problem.schedule.scans_skipped;
  j["detections_skipped"] = problem.schedule.observations_skipped;
  j["steps"] = problem.schedule.steps.size();
  j["lost_runs"] = m.lost;
  // Wilson 95 % interval of the lost fraction (wilson.hpp): compare intervals, not counts.
  const auto ci = wilson95(m.lost, static_cast<double>(s.runs));
  j["lost_fraction_ci95"] = {ci[0], ci[1]};
  j["max_error_m_runs"] = m.max_err;
  j["cholesky_fallbacks"] = m.fallbacks;
  j["particle_failures"] = m.failures;
}

void add_truth_json(nlohmann::json& j, const MclSettings& s, const ReferenceTruth& ref,
                    const std::vector<robot::DetectionResidual>& residuals) {
  j["ground_truth"] = name_of(s.truth);
  if (s.truth == MclTruth::kGps) {
    j["ground_truth_detail"] = "GPS fixes interpolated linearly to the step times";
  } else {
    j["ground_truth_detail"] = fmt::format(
        "weighted mean of a GPS-aided implicit MCL run (config A, GPS std {} m, M = {}, seed 1)",
        s.gps_std, s.reference_particles);
    j["reference_cache"] = ref.cache;
    j["reference_from_cache"] = ref.from_cache;
    j["reference_vs_gps_rmse_m"] = ref.vs_gps;
  }
  std::vector<double> distances;
  for (const auto& r : residuals)
    if (std::isfinite(r.distance)) distances.push_back(r.distance);
  if (distances.empty()) return;
  const double within = static_cast<double>(
      std::count_if(distances.begin(), distances.end(), [](double d) { return d < 0.5; }));
  j["detection_check"] = {
      {"pose", s.truth == MclTruth::kReference ? "reference track" : "GPS track"},
      {"detections_placed", distances.size()},  // those with a truth heading
      {"distance_to_nearest_beacon_median_m", median_of(distances)},
      {"within_0_5_m_fraction", within / static_cast<double>(distances.size())}};
}

/// mcl_detections.csv, the appended row of mcl_summary.csv and mcl_beacons.csv.
void write_mcl_csv(const MclSettings& s, const RunContext& ctx, double p, const MclSummary& m,
                   const LocalizationProblem& problem,
                   const std::vector<robot::DetectionResidual>& residuals) {
  {
    OutputFile output(ctx.csv_path("mcl_detections.csv"));
    std::ostream& d = output.stream();
    d << "time,scan,range,bearing,x,y,nearest_beacon_id,distance\n";
    for (const auto& r : residuals)
      d << fmt::format(
          "{:.6f},{},{:.6f},{:.8f},{:.6f},{:.6f},{},{:.6f}\n", r.time, r.scan, r.z(0), r.z(1),
          r.world(0), r.world(1),
          r.nearest_beacon >= 0 ? problem.map.id(static_cast<std::size_t>(r.nearest_beacon)) : -1,
          r.distance);
    output.commit();
  }
  OutputFile summary(ctx.csv_path("mcl_summary.csv"), OutputFile::Mode::kAppend);
  std::ostream& out = summary.stream();
  if (summary.fresh())
    out << "method,particles,runs,config,p,error_percent_mean,error_percent_std,"
           "error_percent_median,rmse_m,heading_rmse_rad,lost_runs,ess_mean,cpu_ms_per_step,"
           "seed\n";
  out << fmt::format("{},{},{},{},{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{},{:.6f},{:.6f},{}\n",
                     s.method, s.particles, s.runs, name_of(s.config), p, mean_of(m.err),
                     sd_of(m.err), median_of(m.err), mean_of(m.rmse), mean_of(m.hrmse), m.lost,
                     mean_of(m.ess), mean_of(m.cpu), ctx.seed);
  summary.commit();
  OutputFile beacons(ctx.csv_path("mcl_beacons.csv"));
  std::ostream& b = beacons.stream();
  b << "id,x,y\n";
  for (std::size_t k = 0; k < problem.map.size(); ++k)
    b << fmt::format("{},{:.6f},{:.6f}\n", problem.map.id(k), problem.map.position(k)(0),
                     problem.map.position(k)(1));
  beacons.commit();
}

/// The runs of run_mcl for one motion model, and the JSON result.
template <typename Motion>
nlohmann::json run_mcl_model(const MclSettings& s, const RunContext& ctx, const Motion& model,
                             const robot::RangeBearingSensor& sensor, const MclSetup& setup) {
  LocalizationProblem problem = filter::make_problem(setup.log, model.dt());
  warn_skipped_scans("mcl", s.data_dir.empty() ? "data/carpark" : s.data_dir, problem.schedule,
                     model.dt());
  const ReferenceTruth ref =
      s.truth == MclTruth::kReference ? use_reference_truth(problem, s, ctx) : ReferenceTruth{};
  if (s.init != "known" || s.kidnap_at >= 0) return run_mcl_global(s, ctx, model, sensor, problem);

  filter::FilterOptions options;
  options.particles = static_cast<std::size_t>(s.particles);
  options.association.clutter = s.clutter;
  options.association.label_gate = s.label_gate;
  filter::ImplicitProposal implicit_proposal;
  implicit_proposal.map = s.map;
  ProgressBar bar(fmt::format("mcl {} M={}", s.method, s.particles),
                  static_cast<std::size_t>(s.runs), ctx.show_progress(), ctx.progress);
  auto run_number = [&](std::size_t r) {
    // Every particle's randomness comes from Rng({seed * runs + run, step, particle, purpose}).
    filter::FilterOptions o = options;
    o.seed = ctx.seed * static_cast<std::uint64_t>(s.runs) + static_cast<std::uint64_t>(r);
    return s.method == "implicit"
               ? filter::run_localization(problem, model, sensor, implicit_proposal, o)
               : filter::run_localization(problem, model, sensor, filter::BootstrapProposal{}, o);
  };
  const auto records = distribute_runs(
      ctx, "mcl", runs_key(s, ctx, setup), static_cast<std::size_t>(s.runs), [&](std::size_t r) {
        bar.check();  // the bar ticks per run: after a stop, no run starts
        const LocalizationRun run = run_number(r);
        bar.tick();
        return record_of(run, filter::localization_metrics(run, problem.truth, options.particles));
      });
  bar.finish();
  const MclSummary m = summarise(records);
  if (const double g = std::accumulate(m.gated.begin(), m.gated.end(), 0.0); g > 0)
    fmt::print(stderr,
               "implicit mcl: warning: {} labelled detections ({} per run) were left out: the "
               "predicted pose could not produce them (d^2 > --label-gate {:g}); --label-gate 0 "
               "keeps every label (\"labelled_gated\" in the JSON counts them)\n",
               g, g / static_cast<double>(m.gated.size()), s.label_gate);
  // Only rank 0 writes (parallel_runs.hpp), and only the file needs the whole run.
  if (!ctx.out_dir.empty() && rank_index() == 0) {
    // The run with the median err% (the lower median for an even count): a typical run, not the
    // luckiest or a lost one. Recomputed: its result depends only on its number.
    std::vector<std::size_t> order(m.err.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return m.err[a] < m.err[b]; });
    const std::size_t median_run = order[(order.size() - 1) / 2];
    std::string name = fmt::format("mcl_{}_M{}", s.method, s.particles);
    if (s.config != NoiseConfig::kA || s.p >= 0)
      name += fmt::format("_config{}", name_of(s.config));
    if (s.p >= 0) name += fmt::format("_p{}", s.p);
    write_trajectory(ctx.csv_path(name + "_trajectory.csv"), problem, run_number(median_run));
  }
  if (rank_index() == 0 && (!s.trajectory.empty() || !s.truth_trajectory.empty()))
    write_mcl_tum_files(s, problem, run_number(0));

  // Dead reckoning from the prior mean: the error with no laser at all.
  std::vector<Pose> dr;
  Pose x = problem.initial_mean;
  for (std::size_t n = 0; n < problem.schedule.steps.size(); ++n)
    dr.push_back(x = model.with_dt(problem.step_dt[n]).predict(x, problem.schedule.steps[n].u));
  const std::vector<robot::DetectionResidual> residuals = detection_check(setup.log, problem);

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - setup.start).count();
  nlohmann::json j;
  j["method"] = s.method;
  if (s.method == "implicit") j["map"] = name_of(s.map);
  j["particles"] = s.particles;
  j["runs"] = s.runs;
  j["config"] = name_of(s.config);
  j["model"] = setup.model_name;
  j["p"] = setup.p;
  j["q"] = setup.noise.state_sd.at(0);
  j["control_sd"] = setup.noise.control_sd;
  j["state_sd"] = setup.noise.state_sd;
  j["sigma2"] = name_of(s.sigma2);
  j["clutter"] = s.clutter;
  j["seed"] = ctx.seed;
  j["threads"] = active_threads();
  add_summary_json(j, m);
  add_data_json(j, s, m, problem);
  j["dead_reckoning_error_percent"] = filter::error_percent(dr, problem.truth);
  add_truth_json(j, s, ref, residuals);
  j["seconds"] = seconds;
  if (!ctx.out_dir.empty()) write_mcl_csv(s, ctx, setup.p, m, problem, residuals);
  return j;
}

}  // namespace
}  // namespace implicit::experiments
