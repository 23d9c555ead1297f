// SLAM on synthetic Car Park data and on plain-text logs (paper §4.2, Table 6, Figure 7).
//
// K data sets (seeds seed, seed+1, ...; every method sees identical data for a given seed) are run
// in parallel; inside a run the particles are updated in parallel. All randomness comes from
// keyed streams, so the JSON is bit-identical for any --threads (apart from the timings).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "experiments/landmark_slam.hpp"
#include "experiments/motion_models.hpp"
#include "experiments/parallel_runs.hpp"
#include "experiments/tum_output.hpp"
#include "experiments/vehicle.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::experiments {
namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

double mean(const std::vector<double>& v) {
  if (v.empty()) return std::nan("");
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double stddev(const std::vector<double>& v) {
  // A metric that could not be computed (NaN, e.g. the map metrics without a true map) has no
  // spread either, also over a single run: null in the JSON, not 0.
  if (std::any_of(v.begin(), v.end(), [](double x) { return std::isnan(x); })) return std::nan("");
  if (v.size() < 2) return 0.0;
  const double m = mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// Data sets: from --data (a log file, or every *.log / *.log.gz in a folder), else synthetic.
std::vector<slam::SlamDataset> load_logs(const std::filesystem::path& p) {
  std::vector<slam::SlamDataset> out;
  if (std::filesystem::is_directory(p)) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(p)) {
      const std::string n = e.path().filename().string();
      if (n.ends_with(".log") || n.ends_with(".log.gz")) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    require(!files.empty(), "--data {}: expected *.log or *.log.gz files in the folder, got none",
            p.string());
    for (const auto& f : files) out.push_back(slam::read_slam_log(f));
  } else {
    require(std::filesystem::exists(p), "--data: expected an existing file or folder, got '{}'",
            p.string());
    out.push_back(slam::read_slam_log(p));
  }
  return out;
}

void write_csv_outputs(const RunContext& ctx, const std::string& stem, const slam::SlamDataset& d,
                       const slam::SlamRun& run) {
  {
    OutputFile file(ctx.csv_path(stem + "_path.csv"));
    std::ostream& os = file.stream();
    os << "n,x_true,y_true,beta_true,x_hat,y_hat,beta_hat\n";
    for (std::size_t n = 0; n < run.path.size(); ++n) {
      const bool t = n == 0 || d.has_truth(n);
      const slam::Pose truth =
          n == 0 ? d.initial_pose : (t ? d.truth[n] : slam::Pose::Constant(std::nan("")));
      os << fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", n, truth(0), truth(1),
                        truth(2), run.path[n](0), run.path[n](1), run.path[n](2));
    }
    file.commit();
  }
  {
    OutputFile file(ctx.csv_path(stem + "_map.csv"));
    std::ostream& os = file.stream();
    os << "kind,id,x,y\n";
    for (std::size_t k = 0; k < d.landmarks.size(); ++k)
      os << fmt::format("true,{},{:.9g},{:.9g}\n", k, d.landmarks[k](0), d.landmarks[k](1));
    for (std::size_t k = 0; k < run.map.landmarks.size(); ++k)
      os << fmt::format("estimate,{},{:.9g},{:.9g}\n", run.map.ids[k], run.map.landmarks[k](0),
                        run.map.landmarks[k](1));
    file.commit();
  }
}

/// --trajectory: run 0's path; --truth-trajectory: data set 0's truth where it is known. Times
/// are seconds from the first pose (step n at the sum of the first n step lengths).
void write_slam_tum_files(const SlamSettings& s, const slam::SlamDataset& d,
                          const slam::SlamRun& run) {
  if (s.trajectory.empty() && s.truth_trajectory.empty()) return;
  TumTrack est, truth;
  double time = 0.0;
  for (std::size_t n = 0; n < run.path.size(); ++n) {
    if (n > 0) time += d.step_length(n);
    est.add(time, run.path[n]);
    if (n == 0)
      truth.add(time, d.initial_pose);
    else if (d.has_truth(n))
      truth.add(time, d.truth[n]);
  }
  if (!s.trajectory.empty()) est.write(s.trajectory, "slam --trajectory");
  if (s.truth_trajectory.empty()) return;
  require(d.truth_has_heading,
          "slam --truth-trajectory {}: the truth of {} is a position fix without heading; a TUM "
          "file needs the full pose",
          s.truth_trajectory, d.name);
  truth.write(s.truth_trajectory, "slam --truth-trajectory");
}

// What the summary needs of one run. Run 0 also carries its path and map, for the CSV files; with
// the consistent truth, every run carries its NEES per step, for the band.
struct RunSummary {
  std::string name;
  std::size_t steps = 0;
  slam::SlamMetrics metrics;
  slam::SlamRun run;  // stats, wall time, map bytes; path and map of run 0 only
};

SlamRunRecord to_record(const slam::SlamDataset& d, const slam::SlamRun& run,
                        const slam::SlamMetrics& m, bool with_nees, bool with_path) {
  const auto& st = run.stats;
  SlamRunRecord r;
  r.error_percent = m.error_percent;
  r.error_aligned_percent = m.error_aligned_percent;
  r.rmse_pose_m = m.rmse_pose_m;
  r.rmse_pose_aligned_m = m.rmse_pose_aligned_m;
  r.rmse_heading_rad = m.rmse_heading_rad;
  r.rmse_map_m = m.rmse_map_m;
  r.map_shape_m = m.map_shape_m;
  r.nees_mean = m.nees_mean;
  r.landmarks = m.landmarks;
  r.ess_fraction_sum = st.ess_fraction_sum;
  r.weighted_steps = st.weighted_steps;
  r.resamplings = st.resamplings;
  r.newton_iterations = st.newton_iterations;
  r.newton_solves = st.newton_solves;
  r.skipped = st.skipped;
  r.map_bytes = run.map_bytes;
  r.wall_seconds = run.wall_seconds;
  r.steps = d.steps();
  r.scored_steps = m.scored_steps;
  r.name = d.name;
  // The NEES per step (one number per step and run) only where it is summarised.
  if (with_nees) r.nees = m.nees;
  if (with_path) {
    for (const auto& p : run.path) r.path.insert(r.path.end(), {p(0), p(1), p(2)});
    for (std::size_t k = 0; k < run.map.landmarks.size(); ++k)
      r.map.insert(r.map.end(), {static_cast<double>(run.map.ids[k]), run.map.landmarks[k](0),
                                 run.map.landmarks[k](1)});
  }
  return r;
}

RunSummary from_record(const SlamRunRecord& r) {
  RunSummary out;
  auto& m = out.metrics;
  auto& st = out.run.stats;
  m.error_percent = r.error_percent;
  m.error_aligned_percent = r.error_aligned_percent;
  m.rmse_pose_m = r.rmse_pose_m;
  m.rmse_pose_aligned_m = r.rmse_pose_aligned_m;
  m.rmse_heading_rad = r.rmse_heading_rad;
  m.rmse_map_m = r.rmse_map_m;
  m.map_shape_m = r.map_shape_m;
  m.nees_mean = r.nees_mean;
  m.landmarks = r.landmarks;
  st.ess_fraction_sum = r.ess_fraction_sum;
  st.weighted_steps = r.weighted_steps;
  st.resamplings = r.resamplings;
  st.newton_iterations = r.newton_iterations;
  st.newton_solves = r.newton_solves;
  st.skipped = r.skipped;
  out.run.map_bytes = r.map_bytes;
  out.run.wall_seconds = r.wall_seconds;
  out.steps = r.steps;
  m.scored_steps = r.scored_steps;
  out.name = r.name;
  m.nees = r.nees;
  for (std::size_t k = 0; k + 2 < r.path.size(); k += 3)
    out.run.path.emplace_back(r.path[k], r.path[k + 1], r.path[k + 2]);
  for (std::size_t k = 0; k + 2 < r.map.size(); k += 3) {
    out.run.map.ids.push_back(static_cast<int>(r.map[k]));
    out.run.map.landmarks.push_back(slam::Landmark(r.map[k + 1], r.map[k + 2]));
  }
  return out;
}

/// The filters' options (the same motion and sensor models as the data); `particles` is 1 for
/// the EKF.
slam::SlamOptions filter_options(const SlamSettings& s, slam::SlamMethod method, int particles,
                                 bool consistent) {
  slam::SlamOptions base;
  base.method = method;
  base.association = slam::parse_association(s.association);
  base.particles = particles;
  base.min_range = s.min_range;
  base.motion.control_std = Vec<2>(s.control_noise, s.control_noise);
  require(s.range_sd >= 0.0 && s.bearing_sd_deg >= 0.0 && s.gate_chi2 >= 0.0 &&
              s.new_landmark_density >= 0.0,
          "--range-sd, --bearing-sd, --gate-chi2, --new-landmark-density: expected >= 0 (0 = "
          "the default), got {}, {}, {}, {}",
          s.range_sd, s.bearing_sd_deg, s.gate_chi2, s.new_landmark_density);
  if (s.range_sd > 0.0 || s.bearing_sd_deg > 0.0) {
    const Mat<2>& spec = base.sensor.noise_covariance();
    base.sensor = robot::RangeBearingSensor(
        s.range_sd > 0.0 ? s.range_sd * s.range_sd : spec(0, 0),
        s.bearing_sd_deg > 0.0 ? std::pow(s.bearing_sd_deg * kPi / 180.0, 2) : spec(1, 1));
  }
  if (s.gate_chi2 > 0.0) base.gate_chi2 = s.gate_chi2;
  if (s.new_landmark_density > 0.0) base.new_landmark_density = s.new_landmark_density;
  base.motion = ute_params(robot::RobotLog{}, MotionNoise{s.control_sd, s.state_sd}, base.motion);
  if (consistent) {
    const double f = std::sqrt(s.consistent_noise_scale);
    base.motion.control_std *= f;
    base.motion.state_std *= f;
  }
  return base;
}

/// The data of the runs: logs (--data) or the synthetic scenario, and the vehicle they drive.
struct SlamData {
  std::vector<slam::SlamDataset> logs;  ///< empty: synthetic
  slam::SlamScenario scenario;
  std::string model = "ute";
  bool vehicle_assumed = false;  ///< a log declared no vehicle
};

/// The declaration data set d runs with: its own `vehicle` record, else (the Car Park's folders,
/// a log that declares none) the geometry it was read with, keeping the keys the model has.
robot::VehicleDeclaration dataset_declaration(const MotionModelEntry& entry,
                                              const slam::SlamDataset& d) {
  if (!d.vehicle_parameters.empty())
    return full_declaration(entry, {entry.name, d.vehicle_parameters});
  const robot::VehicleDeclaration geometry = robot::declare_vehicle(d.vehicle);
  robot::VehicleDeclaration kept{entry.name, {}};
  for (const VehicleKey& k : entry.keys)
    if (const auto v = geometry.parameter(k.name)) kept.parameters.emplace_back(k.name, *v);
  return full_declaration(entry, kept);
}

/// Resolves the vehicle model of the logs (one for all) and checks what the data allow.
void resolve_log_model(const SlamSettings& s, SlamData& data) {
  for (std::size_t k = 0; k < data.logs.size(); ++k) {
    const std::string& declared = data.logs[k].vehicle_model;
    const std::string m =
        resolve_model("slam", s.model, declared.empty() ? std::nullopt : std::optional(declared),
                      data.logs[k].name);
    require(k == 0 || m == data.model,
            "slam --data: expected logs of one vehicle, got '{}' and '{}'", data.model, m);
    data.model = m;
  }
}

SlamData load_slam_data(const SlamSettings& s, const RunContext& ctx) {
  SlamData data;
  if (!s.data_dir.empty()) {
    data.logs = load_logs(s.data_dir);
    resolve_log_model(s, data);
  } else {
    require(s.model.empty() || s.model == data.model,
            "slam --model {}: the synthetic data are the Car Park's Ute; give a log of that "
            "vehicle with --data (implicit simulate --model {} writes one)",
            s.model, s.model);
    data.scenario = slam::load_carpark_scenario(slam::default_data_dir());
    if (s.dense_landmarks > 0)
      data.scenario =
          slam::make_dense_scenario(data.scenario, s.dense_laps, s.dense_landmarks, ctx.seed);
  }
  // --control-noise is the Ute's P: on another robot it would be ignored, so it is refused there.
  const MotionModelEntry& entry = motion_model(data.model, "slam --model");
  require(entry.car_park_noise || s.control_noise == SlamSettings{}.control_noise,
          "--control-noise {}: that is the Ute's control noise P = diag(p, p); the {}'s is "
          "--control-sd U1 U2 (sd of {})",
          s.control_noise, data.model, entry.controls);
  // Logs that declare no vehicle (neither record nor `# vehicle` comment) run as the Car Park's
  // Ute (or the --model given, with its defaults): said loudly, and recorded in the JSON.
  for (const auto& d : data.logs) {
    if (!d.vehicle_assumed) continue;
    data.vehicle_assumed = true;
    warn_vehicle_assumed("slam", d.name, dataset_declaration(entry, d));
  }
  for (const auto& d : data.logs)
    if (d.detections_unscheduled > 0) {
      robot::StepSchedule skipped;
      skipped.scans_skipped = d.scans_unscheduled;
      skipped.observations_skipped = d.detections_unscheduled;
      warn_skipped_scans("slam", d.name, skipped, d.vehicle.dt);
    }
  // Refused before the runs: a truth file that cannot be written would cost the whole run.
  const auto& logs = data.logs;
  if (!s.truth_trajectory.empty() && !logs.empty())
    require(!logs[0].truth.empty() && logs[0].truth_has_heading,
            "slam --truth-trajectory {}: {} has {}; a TUM file needs the full pose",
            s.truth_trajectory, logs[0].name,
            logs[0].truth.empty() ? "no truth" : "a truth of position fixes without heading");
  return data;
}

/// Run i's filter options: `base` with its seed and the data set's vehicle (and, for a robot
/// other than the Ute, its motion model from the registry).
slam::SlamOptions run_options(const slam::SlamOptions& base, const slam::SlamDataset& d,
                              const std::string& model, const MotionNoise& noise,
                              std::uint64_t seed) {
  slam::SlamOptions opt = base;
  opt.seed = seed;
  opt.motion.dt = d.vehicle.dt;
  opt.motion.wheelbase = d.vehicle.wheelbase;
  opt.motion.encoder_offset = d.vehicle.encoder_offset;
  opt.motion.laser_forward = d.vehicle.laser_forward;
  opt.motion.laser_left = d.vehicle.laser_left;
  const MotionModelEntry& entry = motion_model(model, "slam --model");
  if (!entry.car_park_noise)
    opt.model = make_motion_model(entry, dataset_declaration(entry, d), noise);
  return opt;
}

/// The settings the records depend on (parallel_runs.hpp: the key of --resume).
std::string runs_key(const SlamSettings& s, const RunContext& ctx, int particles,
                     const std::string& model) {
  return fmt::format(
      "seed={} method={} M={} association={} truth={} laser_every={} noise_scale={:a} "
      "dense={}x{} min_range={:a} control_noise={:a} range_sd={:a} bearing_sd={:a} gate={:a} "
      "p0={:a} data={} model={} control_sd={:a} state_sd={:a}",
      ctx.seed, s.method, particles, s.association, name_of(s.truth), s.laser_every,
      s.consistent_noise_scale, s.dense_landmarks, s.dense_laps, s.min_range, s.control_noise,
      s.range_sd, s.bearing_sd_deg, s.gate_chi2, s.new_landmark_density, s.data_dir, model,
      fmt::join(s.control_sd, ","), fmt::join(s.state_sd, ","));
}

/// The per-run values the JSON and the CSV files summarise.
struct SlamColumns {
  std::vector<double> err, err_al, rmse_p, rmse_pa, rmse_h, rmse_m, shape, ess, res, nees, lms,
      mapbytes, newton;
  std::size_t steps = 0, skipped = 0, scored_min = std::numeric_limits<std::size_t>::max();
};

SlamColumns columns_of(const std::vector<RunSummary>& runs) {
  SlamColumns c;
  for (const RunSummary& r : runs) {
    const auto& m = r.metrics;
    const auto& st = r.run.stats;
    c.err.push_back(m.error_percent);
    c.err_al.push_back(m.error_aligned_percent);
    c.rmse_p.push_back(m.rmse_pose_m);
    c.rmse_pa.push_back(m.rmse_pose_aligned_m);
    c.rmse_h.push_back(m.rmse_heading_rad);
    c.rmse_m.push_back(m.rmse_map_m);
    c.shape.push_back(m.map_shape_m);
    c.ess.push_back(st.mean_ess_fraction());
    c.res.push_back(static_cast<double>(st.resamplings));
    c.nees.push_back(m.nees_mean);
    c.lms.push_back(static_cast<double>(m.landmarks));
    c.mapbytes.push_back(static_cast<double>(r.run.map_bytes));
    if (st.newton_solves > 0)
      c.newton.push_back(static_cast<double>(st.newton_iterations) /
                         static_cast<double>(st.newton_solves));
    c.steps += r.steps;
    c.skipped += st.skipped;
    c.scored_min = std::min(c.scored_min, m.scored_steps);
  }
  return c;
}

/// The filter's model, so that a run on real data can be repeated from its JSON alone: the
/// motion noise the filter used (unicycle: its own; --control-noise is the Ute's only) and its
/// laser model.
void add_model_json(nlohmann::json& j, const SlamSettings& s, const std::string& model,
                    const slam::SlamOptions& base) {
  if (const MotionModelEntry& entry = motion_model(model, "slam --model"); !entry.car_park_noise) {
    j["control_noise"] = nullptr;
    j["control_sd"] = s.control_sd.empty() ? entry.default_noise.control_sd : s.control_sd;
    j["state_sd"] = s.state_sd.empty() ? entry.default_noise.state_sd : s.state_sd;
  } else {
    j["control_noise"] = s.control_noise;
    j["control_sd"] = {base.motion.control_std(0), base.motion.control_std(1)};
    j["state_sd"] = {base.motion.state_std(0), base.motion.state_std(1), base.motion.state_std(2)};
  }
  j["range_sd_m"] = std::sqrt(base.sensor.noise_covariance()(0, 0));
  j["bearing_sd_deg"] = std::sqrt(base.sensor.noise_covariance()(1, 1)) * 180.0 / kPi;
  j["gate_chi2"] = base.gate_chi2;
  j["new_landmark_density"] = base.new_landmark_density;
}

/// The means and spreads over the runs (null for the EKF's particle statistics).
void add_metrics_json(nlohmann::json& j, const SlamColumns& c, bool is_ekf) {
  j["error_percent_mean"] = mean(c.err);
  j["error_percent_std"] = stddev(c.err);
  j["error_percent_median"] = median(c.err);
  j["error_aligned_percent_mean"] = mean(c.err_al);
  j["error_aligned_percent_std"] = stddev(c.err_al);
  j["map_shape_m"] = mean(c.shape);
  j["map_shape_m_std"] = stddev(c.shape);
  j["ess_mean"] = is_ekf ? nlohmann::json(nullptr) : nlohmann::json(mean(c.ess));
  j["resamplings"] = is_ekf ? nlohmann::json(nullptr) : nlohmann::json(mean(c.res));
  j["ess_std"] = is_ekf ? nlohmann::json(nullptr) : nlohmann::json(stddev(c.ess));
  j["resamplings_std"] = is_ekf ? nlohmann::json(nullptr) : nlohmann::json(stddev(c.res));
  j["rmse_pose_m"] = mean(c.rmse_p);
  // The names every mcl and slam output shares (docs/cli.md, "Names shared by mcl and slam").
  j["position_rmse_m"] = mean(c.rmse_p);
  j["heading_rmse_rad"] = mean(c.rmse_h);
  j["resamplings_mean"] = j["resamplings"];
  j["rmse_pose_m_std"] = stddev(c.rmse_p);
  j["rmse_pose_aligned_m"] = mean(c.rmse_pa);
  j["rmse_heading_rad"] = mean(c.rmse_h);
  j["rmse_map_m"] = mean(c.rmse_m);
  j["rmse_map_m_std"] = stddev(c.rmse_m);
  j["landmarks_mean"] = mean(c.lms);
  j["map_bytes_mean"] = mean(c.mapbytes);
  if (!c.newton.empty()) j["newton_iterations_per_update"] = mean(c.newton);
}

/// NEES (only meaningful when the truth follows the filter's model): the mean, and the per-step
/// average over the K runs against [chi2_3K(.025)/K, chi2_3K(.975)/K] (spec §4).
void add_nees_json(nlohmann::json& j, const SlamColumns& c, const std::vector<RunSummary>& runs,
                   std::size_t n_steps) {
  j["nees_mean"] = mean(c.nees);
  const double kk = static_cast<double>(runs.size());
  const double lo = slam::chi_square_quantile(0.025, 3 * kk) / kk;
  const double hi = slam::chi_square_quantile(0.975, 3 * kk) / kk;
  std::size_t inside = 0, total = 0;
  for (std::size_t n = 1; n <= n_steps; ++n) {
    double sum = 0.0;
    bool ok = true;
    for (std::size_t i = 0; i < runs.size() && ok; ++i) {
      const auto& v = runs[i].metrics.nees;
      ok = n < v.size() && std::isfinite(v[n]);
      if (ok) sum += v[n];
    }
    if (!ok) continue;
    ++total;
    if (sum / kk >= lo && sum / kk <= hi) ++inside;
  }
  j["nees_band"] = {lo, hi};
  j["nees_fraction_in_band"] =
      total > 0 ? static_cast<double>(inside) / static_cast<double>(total) : 0.0;
}

/// slam_<method>_M<particles>_{path,map,runs}.csv and the appended row of slam_summary.csv.
void write_slam_csv(const SlamSettings& s, const RunContext& ctx, int particles,
                    const nlohmann::json& j, const SlamColumns& c, const slam::SlamDataset& data0,
                    const std::vector<RunSummary>& runs, bool is_ekf) {
  const std::string stem = fmt::format("slam_{}_M{}", s.method, particles);
  write_csv_outputs(ctx, stem, data0, runs[0].run);
  {
    OutputFile file(ctx.csv_path(stem + "_runs.csv"));
    std::ostream& os = file.stream();
    os << "dataset,seed,error_percent,error_aligned_percent,rmse_pose_m,rmse_map_m,map_shape_m,"
          "ess_mean,resamplings,landmarks,nees_mean,wall_ms_per_step\n";
    for (std::size_t i = 0; i < runs.size(); ++i)
      os << fmt::format("{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{:.6g},{:.6g}\n",
                        runs[i].name, ctx.seed + i, c.err[i], c.err_al[i], c.rmse_p[i], c.rmse_m[i],
                        c.shape[i], c.ess[i], c.res[i], c.lms[i], c.nees[i],
                        1e3 * runs[i].run.wall_seconds / static_cast<double>(runs[i].steps));
    file.commit();
  }
  OutputFile summary(ctx.csv_path("slam_summary.csv"), OutputFile::Mode::kAppend);
  std::ostream& os = summary.stream();
  if (summary.fresh())
    os << "method,particles,datasets,association,truth,error_percent_mean,error_percent_std,"
          "error_aligned_percent_mean,map_shape_m,rmse_pose_m,rmse_map_m,ess_mean,resamplings,"
          "cpu_ms_per_step,peak_memory_mb\n";
  os << fmt::format(
      "{},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},"
      "{:.6g},{:.6g}\n",
      s.method, particles, s.datasets, s.association, j["truth"].get<std::string>(), mean(c.err),
      stddev(c.err), mean(c.err_al), mean(c.shape), mean(c.rmse_p), mean(c.rmse_m),
      is_ekf ? 1.0 : mean(c.ess), is_ekf ? 0.0 : mean(c.res), j["cpu_ms_per_step"].get<double>(),
      peak_memory_mb());
  summary.commit();
}

}  // namespace

nlohmann::json run_slam(const SlamSettings& s, const RunContext& ctx) {
  const auto wall0 = std::chrono::steady_clock::now();
  const slam::SlamMethod method = slam::parse_slam_method(s.method);
  require(s.particles >= 1, "--particles: expected >= 1, got {}", s.particles);
  require(s.datasets >= 1, "--datasets: expected >= 1, got {}", s.datasets);
  require(s.laser_every >= 1, "--laser-every: expected >= 1, got {}", s.laser_every);
  const bool consistent = s.truth == slam::TruthMode::kConsistent;
  const bool is_ekf = method == slam::SlamMethod::kEkf;
  const int particles = is_ekf ? 1 : s.particles;
  const slam::SlamOptions base = filter_options(s, method, particles, consistent);
  const SlamData data = load_slam_data(s, ctx);
  const auto& logs = data.logs;
  const MotionNoise noise{s.control_sd, s.state_sd};

  const auto k_runs = static_cast<std::size_t>(s.datasets);
  std::vector<RunSummary> runs(k_runs);
  const double cpu0 = cpu_seconds();
  // Data set i and its filter run depend only on i (seed + i), so the runs can be anywhere.
  auto dataset = [&](std::size_t i) {
    if (!logs.empty()) return logs[i % logs.size()];
    slam::SyntheticConfig cfg;
    cfg.truth = s.truth;
    cfg.laser_every = s.laser_every;
    cfg.motion = base.motion;
    return slam::generate_synthetic(data.scenario, cfg, ctx.seed + i);
  };
  // Progress counts steps, not runs: a single long run (Victoria Park, about a minute) moves too.
  std::size_t total_steps = 0;
  for (std::size_t i = 0; i < k_runs; ++i)
    total_steps += logs.empty() ? 0 : logs[i % logs.size()].steps();
  if (logs.empty()) total_steps = k_runs * dataset(0).steps();  // one scenario: equal lengths
  ProgressBar bar(fmt::format("SLAM {} M={} steps", s.method, particles), total_steps,
                  ctx.show_progress(), ctx.progress);
  const auto records = distribute_runs(
      ctx, "slam", runs_key(s, ctx, particles, data.model), k_runs, [&](std::size_t i) {
        const slam::SlamDataset d = dataset(i);
        const slam::SlamOptions opt = run_options(base, d, data.model, noise, ctx.seed + i);
        const slam::SlamRun run = slam::run_filter(d, opt, false, [&bar] { bar.tick(); });
        return to_record(d, run, slam::evaluate(d, run), consistent, i == 0);
      });
  for (std::size_t i = 0; i < k_runs; ++i) runs[i] = from_record(records[i]);
  bar.finish();
  const double cpu = cpu_seconds() - cpu0;
  const slam::SlamDataset data0 = dataset(0);  // the data of the run the CSV files show
  const SlamColumns c = columns_of(runs);

  nlohmann::json j;
  j["method"] = s.method;
  j["particles"] = particles;
  j["datasets"] = s.datasets;
  j["association"] = s.association;
  j["truth"] = logs.empty() ? std::string(name_of(s.truth)) : "log";
  j["data"] = logs.empty() ? (s.dense_landmarks > 0 ? data.scenario.name : "carpark-synthetic")
                           : data0.name;
  j["model"] = data.model;
  j["vehicle_assumed"] = data.vehicle_assumed;
  j["laser_every"] = s.laser_every;
  add_model_json(j, s, data.model, base);
  j["seed"] = ctx.seed;
  add_metrics_json(j, c, is_ekf);
  // Below min_range (per run, summed), and never scheduled (the log's, once per run).
  j["detections_skipped"] =
      c.skipped + static_cast<std::size_t>(data0.detections_unscheduled) * k_runs;
  j["detections_unscheduled"] = data0.detections_unscheduled;
  if (consistent) add_nees_json(j, c, runs, data0.steps());
  j["cpu_ms_per_step"] = 1e3 * cpu / static_cast<double>(c.steps);
  j["steps_per_dataset"] = data0.steps();
  j["scored_steps_min"] = c.scored_min;  // over the data sets; 0: a run had no step with truth
  j["peak_memory_mb"] = peak_memory_mb();
  j["threads"] = active_threads();
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  if (rank_index() == 0) write_slam_tum_files(s, data0, runs[0].run);
  if (!s.g2o.empty()) {
    // Every rank builds it (cheap) so that the JSON is the same everywhere; rank 0 writes it.
    const SlamPoseGraph g =
        slam_pose_graph(data0, runs[0].run, run_options(base, data0, data.model, noise, ctx.seed));
    j["g2o_point_edges"] = g.graph.point_edges.size();
    j["g2o_detections_unassociated"] = g.unassociated;
    if (rank_index() == 0) robot::write_g2o(s.g2o, g.graph, "slam --g2o");
  }
  if (!ctx.out_dir.empty()) write_slam_csv(s, ctx, particles, j, c, data0, runs, is_ekf);
  return j;
}

}  // namespace implicit::experiments
