#include "implicit/robot/log_format.hpp"

#include "implicit/robot/csv_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
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
    } else {
      p.fail(fmt::format(
          "expected a record kind vehicle|landmark|initial|control|scan|obs|truth, got '{}'",
          printable(kind)));
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

RobotLog read_robot_log(const std::filesystem::path& path) {
  const std::filesystem::path resolved = resolve_data_file(path);
  std::istringstream in(read_text_file(resolved));  // plain or gzip-compressed
  return parse_robot_log(in, resolved.string());
}

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
    if (best < 0 || best_dt > max_offset + 1e-9) {
      ++s.scans_skipped;
      continue;
    }
    FilterStep& step = s.steps[static_cast<std::size_t>(best)];
    if (step.scan >= 0) {
      ++s.scans_skipped;
      continue;
    }
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

TruthTrack interpolate_truth(const RobotLog& log, const StepSchedule& schedule, double max_gap) {
  require(max_gap > 0.0, "interpolate_truth: expected a positive maximum gap, got {} s", max_gap);
  TruthTrack track;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto& tr = log.truth;
  for (const FilterStep& step : schedule.steps) {
    const double t = step.time;
    Vec<2> p(nan, nan);
    double h = nan;
    if (!tr.empty() && t >= tr.front().time && t <= tr.back().time) {
      auto it = std::lower_bound(tr.begin(), tr.end(), t,
                                 [](const TruthRecord& r, double v) { return r.time < v; });
      if (it->time == t) {
        p = it->position;
        if (it->heading) h = *it->heading;
      } else {
        const TruthRecord& b = *it;
        const TruthRecord& a = *(it - 1);
        if (b.time - a.time <= max_gap) {
          const double s = (t - a.time) / (b.time - a.time);
          p = (1.0 - s) * a.position + s * b.position;
          if (a.heading && b.heading) h = *a.heading + s * wrap_angle(*b.heading - *a.heading);
        }
      }
    }
    track.position.push_back(p);
    track.heading.push_back(h);
  }
  return track;
}

}  // namespace implicit::robot
