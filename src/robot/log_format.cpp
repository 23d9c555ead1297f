#include "implicit/robot/log_format.hpp"

#include "implicit/robot/csv_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

class LineParser {
 public:
  LineParser(const std::string& name, std::size_t line, std::string_view text)
      : name_(name), line_(line) {
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r')) ++i;
      if (i >= text.size() || text[i] == '#') break;
      std::size_t j = i;
      while (j < text.size() && text[j] != ' ' && text[j] != '\t' && text[j] != '\r' &&
             text[j] != '#')
        ++j;
      tokens_.emplace_back(text.substr(i, j - i));
      i = j;
    }
  }
  bool empty() const { return tokens_.empty(); }
  const std::string& kind() const { return tokens_[0]; }
  std::size_t fields() const { return tokens_.size() - 1; }

  [[noreturn]] void fail(const std::string& what) const {
    throw ParseError(fmt::format("{}:{}: {}", name_, line_, what));
  }
  /// Requires between lo and hi fields after the record kind.
  void expect_fields(std::size_t lo, std::size_t hi, const char* layout) const {
    if (fields() < lo || fields() > hi)
      fail(fmt::format("record '{}': expected {} ({} to {} fields), got {} fields",
                       printable(kind()), layout, lo, hi, fields()));
  }
  double number(std::size_t k, const char* field) const {
    const std::string& s = tokens_[k];
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size() || !std::isfinite(v))
      fail(fmt::format("field '{}': expected a finite number, got '{}'", field, printable(s)));
    return v;
  }
  int integer(std::size_t k, const char* field) const {
    const std::string& s = tokens_[k];
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || end != s.c_str() + s.size() || v < 0 || v > std::numeric_limits<int>::max())
      fail(fmt::format("field '{}': expected a non-negative integer, got '{}'", field,
                       printable(s)));
    return static_cast<int>(v);
  }
  std::size_t line() const { return line_; }
  const std::string& token(std::size_t k) const { return tokens_[k]; }
  /// A laser reading: a finite number >= 0, or +infinity ("inf": no return).
  double reading(std::size_t k, const std::string& field) const {
    const std::string& s = tokens_[k];
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size() || std::isnan(v) || !(v >= 0))
      fail(fmt::format("field '{}': expected a range >= 0 or inf (no return), got '{}'", field,
                       printable(s)));
    return v;
  }

  /// 'vehicle MODEL key=value ...': the model name, then numeric parameters with unique keys.
  VehicleDeclaration vehicle() const {
    if (fields() < 1)
      fail("record 'vehicle': expected 'vehicle MODEL [key=value ...]', got no model");
    VehicleDeclaration v;
    v.model = tokens_[1];
    if (v.model.find('=') != std::string::npos)
      fail(fmt::format("field 'model': expected a model name (ute, unicycle), got '{}'", v.model));
    for (std::size_t k = 2; k < tokens_.size(); ++k) {
      const std::string& t = tokens_[k];
      const std::size_t eq = t.find('=');
      if (eq == std::string::npos || eq == 0)
        fail(fmt::format("field {}: expected key=value, got '{}'", k, t));
      const std::string key = t.substr(0, eq), text = t.substr(eq + 1);
      char* end = nullptr;
      const double value = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value))
        fail(fmt::format("field '{}': expected a finite number, got '{}'", key, text));
      if (v.parameter(key))
        fail(fmt::format("field '{}': expected each key once, got it a second time", key));
      if (const std::string range = vehicle_parameter_out_of_range(key, value); !range.empty())
        fail(fmt::format("field '{}': expected {}, got '{}'", key, range, text));
      v.parameters.emplace_back(key, value);
    }
    return v;
  }

 private:
  const std::string& name_;
  std::size_t line_;
  std::vector<std::string> tokens_;
};

void require_later(const LineParser& p, double previous, double t, bool has_previous) {
  if (has_previous && !(t > previous))
    p.fail(fmt::format("field 'time': expected a time after {} (previous '{}' record), got {}",
                       previous, p.kind(), t));
}

constexpr int kMaxLaserBeams = 100000;  // as the CARMEN reader: more is not a planar laser

/// 'laser t angle_min angle_increment range_min range_max n r_1 ... r_n' (see LaserScan).
LaserScan laser_record(const LineParser& p) {
  if (p.fields() < 7)
    p.fail(fmt::format(
        "record 'laser': expected 'laser t angle_min angle_increment range_min range_max n r_1 "
        "... r_n' (at least 7 fields), got {} fields",
        p.fields()));
  LaserScan scan;
  scan.time = p.number(1, "time");
  scan.angle_min = p.number(2, "angle_min");
  scan.angle_increment = p.number(3, "angle_increment");
  if (scan.angle_increment == 0)
    p.fail("field 'angle_increment': expected a non-zero beam spacing, got 0");
  scan.range_min = p.number(4, "range_min");
  if (!(scan.range_min >= 0))
    p.fail(fmt::format("field 'range_min': expected >= 0, got {}", scan.range_min));
  scan.range_max = p.number(5, "range_max");
  if (!(scan.range_max > scan.range_min))
    p.fail(fmt::format("field 'range_max': expected more than range_min = {}, got {}",
                       scan.range_min, scan.range_max));
  const int n = p.integer(6, "n");
  if (n < 1 || n > kMaxLaserBeams)
    p.fail(fmt::format("field 'n': expected 1 to {} beams, got {}", kMaxLaserBeams, n));
  if (p.fields() != 6 + static_cast<std::size_t>(n))
    p.fail(fmt::format("field 'n': expected {} readings after it, got {}", n, p.fields() - 6));
  scan.ranges.resize(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < scan.ranges.size(); ++i)
    scan.ranges[i] = p.reading(7 + i, fmt::format("r_{}", i + 1));
  return scan;
}

/// The records of laser runs (map, laser_mount, odometry, laser); false for any other kind.
bool laser_run_record(const LineParser& p, RobotLog& log) {
  const std::string& kind = p.kind();
  if (kind == "map") {
    p.expect_fields(1, 1, "'map FILE' (a file name without blanks)");
    if (log.map)
      p.fail(fmt::format("expected one 'map' record, got a second one (the first: line {})",
                         log.map->line));
    log.map = MapReference{p.token(1), p.line()};
  } else if (kind == "laser_mount") {
    p.expect_fields(3, 3, "'laser_mount x y theta'");
    if (log.laser_mount) p.fail("expected one 'laser_mount' record, got a second one");
    log.laser_mount = LaserMount{p.number(1, "x"), p.number(2, "y"), p.number(3, "theta")};
  } else if (kind == "odometry") {
    p.expect_fields(4, 4, "'odometry t x y theta'");
    const double t = p.number(1, "time");
    require_later(p, log.odometry.empty() ? 0.0 : log.odometry.back().time, t,
                  !log.odometry.empty());
    log.odometry.push_back({t, Pose(p.number(2, "x"), p.number(3, "y"), p.number(4, "theta"))});
  } else if (kind == "laser") {
    LaserScan scan = laser_record(p);
    require_later(p, log.laser_scans.empty() ? 0.0 : log.laser_scans.back().time, scan.time,
                  !log.laser_scans.empty());
    log.laser_scans.push_back(std::move(scan));
  } else {
    return false;
  }
  return true;
}

constexpr const char* kRecordKinds[] = {"vehicle",     "landmark", "initial", "control",
                                        "scan",        "obs",      "truth",   "map",
                                        "laser_mount", "odometry", "laser"};

/// "vehicle|landmark|...", for messages.
std::string record_kinds() {
  std::string all;
  for (const char* k : kRecordKinds) {
    if (!all.empty()) all += '|';
    all += k;
  }
  return all;
}

}  // namespace

std::string vehicle_parameter_out_of_range(std::string_view key, double value) {
  constexpr double kMaxDt = 60.0;     // [s] a control period; longer is not a vehicle log
  constexpr double kMaxSize = 100.0;  // [m] wheelbase and LASER offsets
  if (key == "dt" && !(value > 0.0 && value <= kMaxDt))
    return fmt::format("a time step in (0, {}] s", kMaxDt);
  if (key == "L" && !(value > 0.0 && value <= kMaxSize))
    return fmt::format("a wheelbase in (0, {}] m", kMaxSize);
  if ((key == "H" || key == "a" || key == "b") && !(std::abs(value) <= kMaxSize))
    return fmt::format("an offset in [-{0}, {0}] m", kMaxSize);
  return {};
}

VehicleDeclaration declare_vehicle(const UteParams& p) {
  return {"ute",
          {{"dt", p.dt},
           {"L", p.wheelbase},
           {"H", p.encoder_offset},
           {"a", p.laser_forward},
           {"b", p.laser_left}}};
}

VehicleDeclaration declare_vehicle(const UnicycleParams& p) { return {"unicycle", {{"dt", p.dt}}}; }

namespace {

/// Copies the declared parameters into the named fields; an unknown key is an error.
void read_parameters(const VehicleDeclaration& v,
                     std::initializer_list<std::pair<const char*, double*>> fields) {
  for (const auto& [key, value] : v.parameters) {
    bool known = false;
    for (const auto& [name, target] : fields)
      if (key == name) {
        *target = value;
        known = true;
      }
    if (known) continue;
    std::string names;
    for (const auto& f : fields) names += (names.empty() ? "" : ", ") + std::string(f.first);
    throw InvalidArgument(
        fmt::format("vehicle '{}': expected parameters among {}, got '{}'", v.model, names, key));
  }
}

}  // namespace

UteParams ute_params(const VehicleDeclaration& v, UteParams p) {
  read_parameters(v, {{"dt", &p.dt},
                      {"L", &p.wheelbase},
                      {"H", &p.encoder_offset},
                      {"a", &p.laser_forward},
                      {"b", &p.laser_left}});
  p.validate();
  return p;
}

UnicycleParams unicycle_params(const VehicleDeclaration& v, UnicycleParams p) {
  read_parameters(v, {{"dt", &p.dt}});
  p.validate();
  return p;
}

RobotLog parse_robot_log(std::istream& in, const std::string& name) {
  RobotLog log;
  log.source = name;
  struct PendingId {
    int id;
    std::size_t line;
  };
  std::vector<PendingId> ids;
  std::string text;
  std::size_t line_no = 0;
  int obs_remaining = 0;
  while (std::getline(in, text)) {
    ++line_no;
    LineParser p(name, line_no, text);
    if (p.empty()) continue;
    const std::string& kind = p.kind();
    if (obs_remaining > 0 && kind != "obs")
      p.fail(fmt::format("expected {} more 'obs' line(s) of the scan at t = {}, got '{}'",
                         obs_remaining, log.scans.back().time, printable(kind)));
    if (kind == "vehicle") {
      if (log.vehicle) p.fail("expected one 'vehicle' record, got a second one");
      log.vehicle = p.vehicle();
    } else if (kind == "landmark") {
      p.expect_fields(3, 3, "'landmark id x y'");
      const int id = p.integer(1, "id");
      if (log.landmarks.index_of(id) >= 0)
        p.fail(fmt::format("field 'id': expected a new landmark id, got {} a second time", id));
      log.landmarks.add(id, Landmark(p.number(2, "x"), p.number(3, "y")));
    } else if (kind == "initial") {
      p.expect_fields(7, 7, "'initial t x y heading std_x std_y std_heading'");
      if (log.initial) p.fail("expected one 'initial' record, got a second one");
      PosePrior prior;
      prior.time = p.number(1, "time");
      prior.mean = Pose(p.number(2, "x"), p.number(3, "y"), p.number(4, "heading"));
      prior.std = Vec<3>(p.number(5, "std_x"), p.number(6, "std_y"), p.number(7, "std_heading"));
      const char* names[3] = {"std_x", "std_y", "std_heading"};
      for (int k = 0; k < 3; ++k)
        if (!(prior.std(k) >= 0))
          p.fail(fmt::format("field '{}': expected a non-negative std deviation, got {}", names[k],
                             prior.std(k)));
      prior.line = line_no;
      log.initial = prior;
    } else if (kind == "control") {
      p.expect_fields(3, 3, "'control t u1 u2'");
      const double t = p.number(1, "time");
      require_later(p, log.controls.empty() ? 0.0 : log.controls.back().time, t,
                    !log.controls.empty());
      log.controls.push_back({t, Control(p.number(2, "u1"), p.number(3, "u2"))});
    } else if (kind == "scan") {
      p.expect_fields(2, 2, "'scan t n'");
      const double t = p.number(1, "time");
      require_later(p, log.scans.empty() ? 0.0 : log.scans.back().time, t, !log.scans.empty());
      obs_remaining = p.integer(2, "n");
      log.scans.push_back({t, {}});
    } else if (kind == "obs") {
      if (obs_remaining == 0)
        p.fail(
            "expected an 'obs' line only after a 'scan t n' line announcing it, got an extra one");
      p.expect_fields(2, 3, "'obs range bearing [id]'");
      Observation o;
      o.z = Measurement(p.number(1, "range"), p.number(2, "bearing"));
      if (!(o.z(0) >= 0)) p.fail(fmt::format("field 'range': expected >= 0, got {}", o.z(0)));
      if (p.fields() == 3) {
        o.landmark_id = p.integer(3, "id");
        ids.push_back({o.landmark_id, line_no});
      }
      log.scans.back().observations.push_back(o);
      --obs_remaining;
    } else if (kind == "truth") {
      p.expect_fields(3, 4, "'truth t x y [heading]'");
      TruthRecord r;
      r.time = p.number(1, "time");
      require_later(p, log.truth.empty() ? 0.0 : log.truth.back().time, r.time, !log.truth.empty());
      r.position = Vec<2>(p.number(2, "x"), p.number(3, "y"));
      if (p.fields() == 4) r.heading = p.number(4, "heading");
      log.truth.push_back(r);
    } else if (!laser_run_record(p, log)) {
      p.fail(fmt::format("expected a record kind {}, got '{}'", record_kinds(), printable(kind)));
    }
  }
  if (obs_remaining > 0)
    throw ParseError(fmt::format("{}:{}: expected {} more 'obs' line(s), got the end of the file",
                                 name, line_no, obs_remaining));
  for (const PendingId& pending : ids)
    if (log.landmarks.index_of(pending.id) < 0)
      throw ParseError(
          fmt::format("{}:{}: field 'id': expected a landmark id defined by a "
                      "'landmark' line, got unknown id {}",
                      name, pending.line, pending.id));
  return log;
}

std::filesystem::path map_file(const RobotLog& log) {
  if (!log.map) return {};
  const std::filesystem::path file(log.map->file);
  return file.is_absolute() ? file : std::filesystem::path(log.source).parent_path() / file;
}

bool is_robot_log(std::string_view text) {
  const std::string name;  // LineParser keeps a reference; no message is made here
  std::size_t line_no = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const LineParser p(name, ++line_no, text.substr(start, end - start));
    if (!p.empty())
      return std::find(std::begin(kRecordKinds), std::end(kRecordKinds), p.kind()) !=
             std::end(kRecordKinds);
    start = end + 1;
  }
  return false;
}

RobotLog read_robot_log(const std::filesystem::path& path) {
  const std::filesystem::path resolved = resolve_data_file(path);
  std::istringstream in(read_text_file(resolved));  // plain or gzip-compressed
  RobotLog log = parse_robot_log(in, resolved.string());
  // Checked here, where the folder is known: a missing map would otherwise surface later as a
  // map reader's error that does not say which log named it.
  if (log.map && !std::filesystem::is_regular_file(map_file(log)))
    throw ParseError(fmt::format(
        "{}:{}: field 'file': expected an existing map file (relative to the log's folder), got "
        "'{}' (no file {})",
        log.source, log.map->line, printable(log.map->file), map_file(log).string()));
  return log;
}

namespace {

void write_laser_run_records(std::ostream& out, const RobotLog& log) {
  if (log.map) {
    const std::string& f = log.map->file;
    require(!f.empty() && f.find_first_of(" \t\r\n#") == std::string::npos,
            "write_robot_log: expected a map file name without blanks or '#' (a 'map' record "
            "holds one word), got '{}'",
            printable(f));
    out << "map " << f << "\n";
  }
  if (log.laser_mount)
    out << fmt::format("laser_mount {:.17g} {:.17g} {:.17g}\n", log.laser_mount->x,
                       log.laser_mount->y, log.laser_mount->yaw);
  for (const OdometryRecord& o : log.odometry)
    out << fmt::format("odometry {:.17g} {:.17g} {:.17g} {:.17g}\n", o.time, o.pose(0), o.pose(1),
                       o.pose(2));
  std::string line;
  for (const LaserScan& s : log.laser_scans) {
    line = fmt::format("laser {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {}", s.time, s.angle_min,
                       s.angle_increment, s.range_min, s.range_max, s.ranges.size());
    for (double r : s.ranges) fmt::format_to(std::back_inserter(line), " {:.17g}", r);
    out << line << "\n";
  }
}

}  // namespace

void write_robot_log(std::ostream& out, const RobotLog& log) {
  out << "# implicit robot log v1 (docs/formats.md)\n";
  if (log.vehicle) {
    out << "vehicle " << log.vehicle->model;
    for (const auto& [key, value] : log.vehicle->parameters)
      out << fmt::format(" {}={:.17g}", key, value);
    out << "\n";
  }
  for (std::size_t k = 0; k < log.landmarks.size(); ++k) {
    const Landmark& m = log.landmarks.position(k);
    out << fmt::format("landmark {} {:.17g} {:.17g}\n", log.landmarks.id(k), m(0), m(1));
  }
  if (log.initial) {
    const PosePrior& p = *log.initial;
    out << fmt::format("initial {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", p.time,
                       p.mean(0), p.mean(1), p.mean(2), p.std(0), p.std(1), p.std(2));
  }
  for (const TimedControl& c : log.controls)
    out << fmt::format("control {:.17g} {:.17g} {:.17g}\n", c.time, c.u(0), c.u(1));
  for (const ObservationSet& s : log.scans) {
    out << fmt::format("scan {:.17g} {}\n", s.time, s.observations.size());
    for (const Observation& o : s.observations) {
      if (o.landmark_id >= 0)
        out << fmt::format("obs {:.17g} {:.17g} {}\n", o.z(0), o.z(1), o.landmark_id);
      else
        out << fmt::format("obs {:.17g} {:.17g}\n", o.z(0), o.z(1));
    }
  }
  write_laser_run_records(out, log);
  for (const TruthRecord& r : log.truth) {
    if (r.heading)
      out << fmt::format("truth {:.17g} {:.17g} {:.17g} {:.17g}\n", r.time, r.position(0),
                         r.position(1), *r.heading);
    else
      out << fmt::format("truth {:.17g} {:.17g} {:.17g}\n", r.time, r.position(0), r.position(1));
  }
}

void write_robot_log(const std::filesystem::path& path, const RobotLog& log) {
  std::ostringstream out;
  write_robot_log(out, log);
  write_text_file(path, out.str());  // gzip when the name ends in .gz
}

StepSchedule make_schedule(const RobotLog& log, double start_time, double max_offset) {
  StepSchedule s;
  for (const TimedControl& c : log.controls)
    if (c.time >= start_time - 1e-9) s.steps.push_back({c.time, c.u, -1});
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    const double t = log.scans[k].time;
    // Nearest step by binary search over the (increasing) step times.
    auto it = std::lower_bound(s.steps.begin(), s.steps.end(), t,
                               [](const FilterStep& st, double v) { return st.time < v; });
    std::ptrdiff_t best = -1;
    double best_dt = std::numeric_limits<double>::infinity();
    // The candidates are the steps either side of t; `it - 1` is only formed when it exists
    // (an iterator before begin() is undefined behaviour even if never dereferenced).
    const auto first = static_cast<std::size_t>(it - s.steps.begin());
    for (std::size_t c = first == 0 ? 0 : first - 1; c <= first && c < s.steps.size(); ++c) {
      const double d = std::abs(s.steps[c].time - t);
      if (d < best_dt) {
        best_dt = d;
        best = static_cast<std::ptrdiff_t>(c);
      }
    }
    const FilterStep* near = best < 0 ? nullptr : &s.steps[static_cast<std::size_t>(best)];
    if (near == nullptr || best_dt > max_offset + 1e-9 || near->scan >= 0) {
      ++s.scans_skipped;
      s.observations_skipped += static_cast<int>(log.scans[k].observations.size());
      continue;
    }
    FilterStep& step = s.steps[static_cast<std::size_t>(best)];
    step.scan = static_cast<int>(k);
    ++s.scans_used;
    if (!log.scans[k].observations.empty()) ++s.scans_with_observations;
    s.observations_used += static_cast<int>(log.scans[k].observations.size());
  }
  return s;
}

void require_runnable(const RobotLog& log) {
  const std::string source = log.source.empty() ? std::string("robot log") : log.source;
  if (!log.initial)
    throw ParseError(
        fmt::format("{}: expected an 'initial' record (the prior pose), got none", source));
  const double t0 = log.initial->time;
  const bool any = std::any_of(log.controls.begin(), log.controls.end(),
                               [t0](const TimedControl& c) { return c.time >= t0 - 1e-9; });
  if (!any)
    throw ParseError(fmt::format(
        "{}:{}: expected 'control' records at or after the 'initial' time {}, got {}", source,
        log.initial->line, t0,
        log.controls.empty() ? std::string("none in the file")
                             : fmt::format("{} all earlier (the last at {})", log.controls.size(),
                                           log.controls.back().time)));
}

std::vector<double> step_lengths(const RobotLog& log, const StepSchedule& schedule,
                                 double nominal_dt) {
  std::vector<double> lengths;
  if (schedule.steps.empty()) return lengths;
  lengths.reserve(schedule.steps.size());
  double previous = log.initial ? log.initial->time : schedule.steps.front().time;
  const auto first =
      std::lower_bound(log.controls.begin(), log.controls.end(), schedule.steps.front().time,
                       [](const TimedControl& c, double t) { return c.time < t; });
  if (first != log.controls.begin()) previous = (first - 1)->time;
  for (const FilterStep& step : schedule.steps) {
    double length = step.time - previous;
    if (std::abs(length - nominal_dt) <= 1e-9 || length <= 0.0) length = nominal_dt;
    lengths.push_back(length);
    previous = step.time;
  }
  return lengths;
}

}  // namespace implicit::robot
