// SLAM data sets: synthetic generation (spec §3.6), reference CSV files, the plain-text log.
#include "implicit/slam/dataset.hpp"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::slam {
namespace {

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  return out;
}

std::vector<std::string> split_ws(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream is(line);
  std::string tok;
  while (is >> tok) out.push_back(tok);
  return out;
}

double to_double(const std::string& s, const std::filesystem::path& file, std::size_t line,
                 const std::string& field) {
  if (s == "nan" || s == "NaN") return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || std::isinf(v))
    throw ParseError(fmt::format("{}:{}: field '{}': expected a number, got '{}'", file.string(),
                                 line, printable(field), printable(s)));
  return v;
}

// For fields with no "missing" reading (landmark positions, controls): NaN is an error too.
double to_finite(const std::string& s, const std::filesystem::path& file, std::size_t line,
                 const std::string& field) {
  const double v = to_double(s, file, line, field);
  if (std::isnan(v))
    throw ParseError(fmt::format("{}:{}: field '{}': expected a finite number, got '{}'",
                                 file.string(), line, field, printable(s)));
  return v;
}

// The fields of a CSV row, which must have as many as the header.
std::vector<std::string> row_fields(const std::string& row, std::size_t columns,
                                    const std::filesystem::path& file, std::size_t line) {
  auto f = split(row, ',');
  if (f.size() != columns)
    throw ParseError(
        fmt::format("{}:{}: expected {} fields, got {}", file.string(), line, columns, f.size()));
  return f;
}

long to_int(const std::string& s, const std::filesystem::path& file, std::size_t line,
            const std::string& field) {
  long v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size())
    throw ParseError(fmt::format("{}:{}: field '{}': expected an integer, got '{}'", file.string(),
                                 line, printable(field), printable(s)));
  return v;
}

std::size_t column(const std::vector<std::string>& header, const std::string& name,
                   const std::filesystem::path& file) {
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end())
    throw ParseError(
        fmt::format("{}:1: expected a column '{}' in the header", file.string(), name));
  return static_cast<std::size_t>(it - header.begin());
}

Measurement observe(const robot::RangeBearingSensor& s, const Pose& x, const Landmark& m) {
  Measurement h = s.predict(x, m);
  h(1) = wrap_angle(h(1));
  return h;
}

}  // namespace

void SlamDataset::validate() const {
  require(offsets.size() == controls.size() + 1,
          "SLAM data set '{}': expected {} step offsets, got {}", name, controls.size() + 1,
          offsets.size());
  require(initial_pose.allFinite(), "SLAM data set '{}': expected a finite initial pose", name);
  for (std::size_t n = 1; n <= steps(); ++n) {
    const Control& u = control(n);
    require(u.allFinite(), "SLAM data set '{}', step {}: expected a finite control, got ({}, {})",
            name, n, u(0), u(1));
    for (const Observation& o : observations(n)) {
      require(o.z.allFinite(),
              "SLAM data set '{}', step {}: expected a finite observation, got (range {}, "
              "bearing {})",
              name, n, o.z(0), o.z(1));
      require(o.z(0) > 0.0, "SLAM data set '{}', step {}: expected a positive range, got {}", name,
              n, o.z(0));
      require(o.landmark < static_cast<int>(landmarks.size()) || landmarks.empty(),
              "SLAM data set '{}', step {}: expected a landmark id below {}, got {}", name, n,
              landmarks.size(), o.landmark);
    }
  }
  require(truth.empty() || truth.size() == controls.size() + 1,
          "SLAM data set '{}': expected {} truth rows, got {}", name, controls.size() + 1,
          truth.size());
  require(step_dt.empty() || step_dt.size() == controls.size(),
          "SLAM data set '{}': expected {} step lengths, got {}", name, controls.size(),
          step_dt.size());
  for (std::size_t n = 0; n < step_dt.size(); ++n)
    require(step_dt[n] > 0 && std::isfinite(step_dt[n]),
            "SLAM data set '{}', step {}: expected a positive step length, got {}", name, n + 1,
            step_dt[n]);
}

std::vector<Pose> integrate_controls(const robot::UteModel& model, const Pose& x0,
                                     std::span<const Control> controls) {
  std::vector<Pose> x(controls.size() + 1);
  x[0] = x0;
  for (std::size_t n = 0; n < controls.size(); ++n) x[n + 1] = model.predict(x[n], controls[n]);
  return x;
}

SlamDataset generate_synthetic(const SlamScenario& sc, const SyntheticConfig& cfg,
                               std::uint64_t seed) {
  require(cfg.laser_every >= 1, "synthetic SLAM data: expected laser_every >= 1, got {}",
          cfg.laser_every);
  require(cfg.max_range > 0, "synthetic SLAM data: expected max_range > 0, got {}", cfg.max_range);
  require(!sc.controls.empty(), "synthetic SLAM data: expected controls, got none");
  SlamDataset d;
  d.name =
      fmt::format("{}_{}_le{}_seed{}", sc.name,
                  cfg.truth == TruthMode::kPaper ? "paper" : "consistent", cfg.laser_every, seed);
  d.vehicle = sc.vehicle;
  d.initial_pose = sc.initial_pose;
  d.landmarks = sc.landmarks;
  robot::UteParams motion = cfg.motion;
  motion.dt = sc.vehicle.dt;
  motion.wheelbase = sc.vehicle.wheelbase;
  motion.encoder_offset = sc.vehicle.encoder_offset;
  motion.laser_forward = sc.vehicle.laser_forward;
  motion.laser_left = sc.vehicle.laser_left;
  const robot::UteModel model(motion);
  const Mat<2> sqrt_r = cfg.sensor.noise_covariance().cwiseSqrt();

  d.truth.resize(sc.controls.size() + 1);
  d.truth[0] = sc.initial_pose;
  SlamDatasetBuilder b(d);
  std::vector<int> visible;
  visible.reserve(sc.landmarks.size());
  for (std::size_t n = 1; n <= sc.controls.size(); ++n) {
    const Control& u = sc.controls[n - 1];
    b.begin_step(u);
    const Pose& prev = d.truth[n - 1];
    if (cfg.truth == TruthMode::kPaper) {
      d.truth[n] = model.predict(prev, u);
    } else {
      Rng rng({seed, n, 1, purpose::kData});
      const Eigen::LLT<Mat<3>> llt(model.process_covariance(prev, u));
      d.truth[n] = model.predict(prev, u) + llt.matrixL() * rng.normal_vector<3>();
    }
    if (n % static_cast<std::size_t>(cfg.laser_every) != 0) continue;
    visible.clear();
    for (std::size_t k = 0; k < sc.landmarks.size(); ++k) {
      const Measurement h = observe(cfg.sensor, d.truth[n], sc.landmarks[k]);
      if (h(0) <= cfg.max_range && h(0) >= cfg.min_range && h(1) >= 0.0 && h(1) <= kPi)
        visible.push_back(static_cast<int>(k));
    }
    if (visible.empty()) continue;
    Rng rng({seed, n, 0, purpose::kData});
    const auto pick =
        std::min(visible.size() - 1, static_cast<std::size_t>(rng.uniform() * visible.size()));
    const int id = visible[pick];
    Observation o;
    o.landmark = id;
    o.z = observe(cfg.sensor, d.truth[n], sc.landmarks[static_cast<std::size_t>(id)]) +
          sqrt_r * rng.normal_vector<2>();
    // A range-finder returns no negative range: with the path passing 0.1-0.4 m from a beacon
    // the noise (sd 0.22 m) occasionally makes z_r <= 0; such a detection is dropped.
    if (o.z(0) > 0.0) b.add_observation(o);
  }
  return d;
}

SlamScenario make_dense_scenario(const SlamScenario& base, int laps, int landmarks,
                                 std::uint64_t seed) {
  require(laps >= 1, "dense SLAM scenario: expected laps >= 1, got {}", laps);
  require(landmarks >= 1, "dense SLAM scenario: expected landmarks >= 1, got {}", landmarks);
  SlamScenario s = base;
  s.name = fmt::format("dense{}x{}", landmarks, laps);
  s.controls.clear();
  for (int l = 0; l < laps; ++l)
    s.controls.insert(s.controls.end(), base.controls.begin(), base.controls.end());
  const robot::UteModel model(s.vehicle);
  const auto path = integrate_controls(model, s.initial_pose, s.controls);
  s.landmarks.resize(static_cast<std::size_t>(landmarks));
  for (int i = 0; i < landmarks; ++i) {
    Rng rng({seed, static_cast<std::uint64_t>(i), 2, purpose::kData});
    const auto at =
        static_cast<std::size_t>((i + 0.5) * static_cast<double>(path.size() - 1) / landmarks);
    const Pose& p = path[at];
    const double side = rng.uniform() < 0.5 ? -1.0 : 1.0;
    const double lateral = side * (3.0 + 9.0 * rng.uniform());
    const double along = 4.0 * (rng.uniform() - 0.5);
    const double c = std::cos(p(2)), sn = std::sin(p(2));
    s.landmarks[static_cast<std::size_t>(i)] =
        Landmark(p(0) + along * c - lateral * sn, p(1) + along * sn + lateral * c);
  }
  return s;
}

std::filesystem::path default_data_dir() { return find_share_dir("data", "IMPLICIT_DATA_DIR"); }

std::vector<std::string> read_text_lines(const std::filesystem::path& path) {
  // One reader for every text file (gzip, size bound, errors naming the file): robot's.
  const std::string text = robot::read_text_file(path);
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::size_t stop = end;
    if (stop > start && text[stop - 1] == '\r') --stop;
    lines.emplace_back(text, start, stop - start);
    start = end + 1;
  }
  return lines;
}

SlamScenario load_carpark_scenario(const std::filesystem::path& data_dir) {
  const auto dir = data_dir / "slam-synthetic";
  SlamScenario s;
  {
    const auto file = dir / "carpark_controls.csv";
    const auto lines = read_text_lines(file);
    require(!lines.empty(), "{}: expected a header line, got an empty file", file.string());
    const auto header = split(lines[0], ',');
    const auto cvc = column(header, "vc", file), cal = column(header, "alpha", file);
    for (std::size_t i = 1; i < lines.size(); ++i) {
      if (lines[i].empty()) continue;
      const auto f = row_fields(lines[i], header.size(), file, i + 1);
      s.controls.emplace_back(to_finite(f[cvc], file, i + 1, "vc"),
                              to_finite(f[cal], file, i + 1, "alpha"));
    }
  }
  {
    const auto file = dir / "landmarks.csv";
    const auto lines = read_text_lines(file);
    require(!lines.empty(), "{}: expected a header line, got an empty file", file.string());
    const auto header = split(lines[0], ',');
    const auto cx = column(header, "east_m", file), cy = column(header, "north_m", file);
    for (std::size_t i = 1; i < lines.size(); ++i) {
      if (lines[i].empty()) continue;
      const auto f = row_fields(lines[i], header.size(), file, i + 1);
      s.landmarks.emplace_back(to_finite(f[cx], file, i + 1, "east_m"),
                               to_finite(f[cy], file, i + 1, "north_m"));
    }
  }
  return s;
}

SlamDataset read_reference_csv(const std::filesystem::path& path,
                               const std::vector<Landmark>& landmarks) {
  const auto lines = read_text_lines(path);
  require(lines.size() >= 2, "{}: expected a header and rows, got {} lines", path.string(),
          lines.size());
  const auto header = split(lines[0], ',');
  const std::size_t c_vc = column(header, "vc", path), c_al = column(header, "alpha", path),
                    c_x = column(header, "x_true", path), c_y = column(header, "y_true", path),
                    c_b = column(header, "beta_true", path),
                    c_has = column(header, "has_obs", path), c_zr = column(header, "z_r", path),
                    c_zb = column(header, "z_b", path), c_id = column(header, "landmark", path);
  SlamDataset d;
  d.name = path.stem().stem().string();
  d.landmarks = landmarks;
  SlamDatasetBuilder b(d);
  for (std::size_t i = 1; i < lines.size(); ++i) {
    if (lines[i].empty()) continue;
    const auto f = row_fields(lines[i], header.size(), path, i + 1);
    const Pose x(to_double(f[c_x], path, i + 1, "x_true"), to_double(f[c_y], path, i + 1, "y_true"),
                 to_double(f[c_b], path, i + 1, "beta_true"));
    d.truth.push_back(x);
    if (i == 1) {
      d.initial_pose = x;
      continue;
    }
    b.begin_step(
        Control(to_double(f[c_vc], path, i + 1, "vc"), to_double(f[c_al], path, i + 1, "alpha")));
    if (to_int(f[c_has], path, i + 1, "has_obs") != 0) {
      Observation o;
      o.z = Measurement(to_double(f[c_zr], path, i + 1, "z_r"),
                        to_double(f[c_zb], path, i + 1, "z_b"));
      o.landmark = static_cast<int>(to_int(f[c_id], path, i + 1, "landmark"));
      b.add_observation(o);
    }
  }
  d.validate();
  return d;
}

std::vector<Pose> read_reference_trace(const std::filesystem::path& path) {
  const auto lines = read_text_lines(path);
  require(!lines.empty(), "{}: expected a header line, got an empty file", path.string());
  const auto header = split(lines[0], ',');
  const auto cx = column(header, "x_hat", path), cy = column(header, "y_hat", path),
             cb = column(header, "beta_hat", path);
  std::vector<Pose> out;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    if (lines[i].empty()) continue;
    const auto f = row_fields(lines[i], header.size(), path, i + 1);
    out.emplace_back(to_double(f[cx], path, i + 1, "x_hat"),
                     to_double(f.at(cy), path, i + 1, "y_hat"),
                     to_double(f.at(cb), path, i + 1, "beta_hat"));
  }
  return out;
}

// ---- the plain-text robot log (implicit/robot/log_format.hpp) ----------------------------
namespace {
// Optional geometry comment: "# vehicle dt=0.025 L=2.83 H=0.76 a=0.95 b=0.5" (other readers
// ignore comments; the Car Park values are the default). Nothing when there is no such comment.
std::optional<robot::UteParams> vehicle_from_comments(const std::vector<std::string>& lines,
                                                      const std::filesystem::path& path) {
  robot::UteParams v;
  bool found = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto f = split_ws(lines[i]);
    if (f.size() < 2 || f[0] != "#" || f[1] != "vehicle") continue;
    found = true;
    for (std::size_t k = 2; k < f.size(); ++k) {
      const auto eq = f[k].find('=');
      if (eq == std::string::npos)
        throw ParseError(fmt::format("{}:{}: vehicle comment: expected key=value, got '{}'",
                                     path.string(), i + 1, printable(f[k])));
      const std::string key = f[k].substr(0, eq);
      if (key != "dt" && key != "L" && key != "H" && key != "a" && key != "b")
        throw ParseError(fmt::format("{}:{}: vehicle comment: expected dt|L|H|a|b, got '{}'",
                                     path.string(), i + 1, printable(key)));
      const double val = to_double(f[k].substr(eq + 1), path, i + 1, key);
      // A NaN here drops every observation and a huge dt turns every metric into NaN, both
      // silently, so the ranges (the `vehicle` record's) are checked where the line is known.
      if (const std::string range = robot::vehicle_parameter_out_of_range(key, val); !range.empty())
        throw ParseError(fmt::format("{}:{}: vehicle comment: field '{}': expected {}, got '{}'",
                                     path.string(), i + 1, key, range,
                                     printable(f[k].substr(eq + 1))));
      if (key == "dt")
        v.dt = val;
      else if (key == "L")
        v.wheelbase = val;
      else if (key == "H")
        v.encoder_offset = val;
      else if (key == "a")
        v.laser_forward = val;
      else
        v.laser_left = val;
    }
  }
  if (!found) return std::nullopt;
  v.validate();
  return v;
}
}  // namespace

SlamDataset dataset_from_robot_log(const robot::RobotLog& log, const robot::UteParams& vehicle,
                                   const std::string& name) {
  robot::require_runnable(log);
  SlamDataset d;
  d.name = name;
  d.vehicle = vehicle;
  d.initial_pose = log.initial->mean;
  // Known ids become indices 0..K-1 in the order of the landmark records.
  for (std::size_t k = 0; k < log.landmarks.size(); ++k)
    d.landmarks.push_back(log.landmarks.position(k));
  if (log.vehicle) {
    d.vehicle_model = log.vehicle->model;
    d.vehicle_parameters = log.vehicle->parameters;
  }
  const auto schedule = robot::make_schedule(log, log.initial->time, 0.5 * vehicle.dt);
  d.scans_unscheduled = schedule.scans_skipped;
  d.detections_unscheduled = schedule.observations_skipped;
  d.step_dt = robot::step_lengths(log, schedule, vehicle.dt);
  // Regular data keep the nominal step (and the Ute model itself, bit for bit).
  if (std::all_of(d.step_dt.begin(), d.step_dt.end(), [&](double t) { return t == vehicle.dt; }))
    d.step_dt.clear();
  SlamDatasetBuilder b(d);
  for (const auto& st : schedule.steps) {
    b.begin_step(st.u);
    if (st.scan < 0) continue;
    const auto& scan = log.scans[static_cast<std::size_t>(st.scan)];
    for (const auto& o : scan.observations) {
      Observation obs;
      obs.z = o.z;
      obs.landmark = o.landmark_id >= 0 ? log.landmarks.index_of(o.landmark_id) : -1;
      require(o.landmark_id < 0 || obs.landmark >= 0,
              "log '{}': the scan at t = {} names landmark id {}, which the map does not have",
              name, scan.time, o.landmark_id);
      b.add_observation(obs);
    }
  }
  if (!log.truth.empty()) {
    const auto track = robot::interpolate_truth(log, schedule);
    d.truth.assign(d.steps() + 1, Pose::Constant(std::numeric_limits<double>::quiet_NaN()));
    d.truth_valid.assign(d.steps() + 1, 0);
    d.truth_has_heading = true;
    for (std::size_t n = 1; n <= d.steps(); ++n) {
      const auto& p = track.position[n - 1];
      if (!p.allFinite()) continue;
      d.truth[n] = Pose(p(0), p(1), track.heading[n - 1]);
      d.truth_valid[n] = 1;
      if (!std::isfinite(track.heading[n - 1])) d.truth_has_heading = false;
    }
  }
  d.validate();
  return d;
}

SlamDataset dataset_from_robot_log(const robot::RobotLog& log, double dt, const std::string& name) {
  robot::UteParams vehicle;
  vehicle.dt = dt;
  vehicle.validate();
  return dataset_from_robot_log(log, vehicle, name);
}

SlamDataset read_slam_log(const std::filesystem::path& path) {
  const auto lines = read_text_lines(path);
  std::string text;
  for (const auto& l : lines) {
    text += l;
    text += '\n';
  }
  std::istringstream in(text);
  const robot::RobotLog log = robot::parse_robot_log(in, path.string());
  robot::UteParams vehicle;
  bool assumed = false;
  try {
    if (!log.vehicle) {
      const auto commented = vehicle_from_comments(lines, path);  // the older convention
      assumed = !commented;
      if (commented) vehicle = *commented;
    } else if (log.vehicle->model == "ute") {
      vehicle = robot::ute_params(*log.vehicle);
    } else {
      // Another robot: the data set needs only its nominal step (the filter brings the model).
      // The shipped unicycle's keys are checked as `mcl` checks them: an unknown one is refused.
      if (log.vehicle->model == "unicycle") (void)robot::unicycle_params(*log.vehicle);
      if (const auto dt = log.vehicle->parameter("dt")) {
        vehicle.dt = *dt;
        vehicle.validate();
      }
    }
  } catch (const InvalidArgument& e) {  // the declaration's own message names no file
    throw InvalidArgument(fmt::format("{}: {}", path.string(), e.what()));
  }
  std::string name = path.filename().string();
  for (const char* ext : {".gz", ".txt", ".log"})
    if (name.size() > std::strlen(ext) && name.ends_with(ext))
      name.resize(name.size() - std::strlen(ext));
  SlamDataset d = dataset_from_robot_log(log, vehicle, name);
  d.vehicle_assumed = assumed;
  return d;
}

void write_slam_log(const SlamDataset& d, const std::filesystem::path& path) {
  robot::RobotLog log;
  for (std::size_t k = 0; k < d.landmarks.size(); ++k)
    log.landmarks.add(static_cast<int>(k), d.landmarks[k]);
  if (d.vehicle_model.empty() || d.vehicle_model == "ute") {
    log.vehicle = robot::declare_vehicle(d.vehicle);
  } else {
    log.vehicle = robot::VehicleDeclaration{d.vehicle_model, d.vehicle_parameters};
    if (!log.vehicle->parameter("dt")) log.vehicle->parameters.emplace_back("dt", d.vehicle.dt);
  }
  log.initial = robot::PosePrior{0.0, d.initial_pose, Vec<3>::Zero()};
  double t = 0.0;
  for (std::size_t n = 1; n <= d.steps(); ++n) {
    t = d.step_dt.empty() ? d.vehicle.dt * static_cast<double>(n) : t + d.step_dt[n - 1];
    log.controls.push_back({t, d.control(n)});
    const auto obs = d.observations(n);
    if (!obs.empty()) {
      robot::ObservationSet set;
      set.time = t;
      for (const auto& o : obs) set.observations.push_back({o.z, o.landmark});
      log.scans.push_back(std::move(set));
    }
    if (d.has_truth(n)) {
      robot::TruthRecord r;
      r.time = t;
      r.position = d.truth[n].head<2>();
      if (d.truth_has_heading) r.heading = d.truth[n](2);
      log.truth.push_back(r);
    }
  }
  robot::write_robot_log(path, log);  // gzip when the name ends in .gz
}

}  // namespace implicit::slam
