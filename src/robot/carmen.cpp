#include "implicit/robot/carmen.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

// Far above any planar laser (a SICK gives 181 or 361 beams, a Hokuyo 1081), far below what would
// make a corrupt count allocate gigabytes.
constexpr long kMaxReadings = 100000;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// The fields of one line, with accessors that fail with the file, the line, the message and
/// the field. Field 0 is the message name.
class Fields {
 public:
  Fields(std::string_view file, std::size_t line, std::string_view text)
      : file_(file), line_(line) {
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && is_blank(text[i])) ++i;
      if (i >= text.size()) break;
      std::size_t j = i;
      while (j < text.size() && !is_blank(text[j])) ++j;
      tokens_.push_back(text.substr(i, j - i));
      i = j;
    }
  }

  bool empty() const { return tokens_.empty(); }
  std::string_view kind() const { return tokens_[0]; }
  /// Fields after the message name.
  std::size_t count() const { return tokens_.size() - 1; }
  std::size_t line() const { return line_; }

  /// Throws "file:line: MESSAGE what".
  [[noreturn]] void fail(std::string_view what) const {
    throw ParseError(fmt::format("{}:{}: {} {}", file_, line_, printable(kind(), 40), what));
  }
  /// Throws "file:line: what".
  [[noreturn]] void fail_line(std::string_view what) const {
    throw ParseError(fmt::format("{}:{}: {}", file_, line_, what));
  }

  /// Field k as a finite number.
  double number(std::size_t k, std::string_view field) const {
    double v = 0.0;
    if (!parse(tokens_[k], v))
      fail(fmt::format("field '{}': expected a finite number, got '{}'", field,
                       printable(tokens_[k])));
    return v;
  }

  /// Field k as an integer in [lo, hi].
  long integer(std::size_t k, std::string_view field, long lo, long hi) const {
    const std::string_view s = tokens_[k];
    long v = 0;
    const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (error != std::errc() || end != s.data() + s.size())
      fail(fmt::format("field '{}': expected an integer, got '{}'", field, printable(s)));
    if (v < lo || v > hi)
      fail(fmt::format("field '{}': expected an integer from {} to {}, got {}", field, lo, hi, v));
    return v;
  }

  /// Fields first .. first + n - 1 as ranges [m]: finite and >= 0.
  std::vector<double> ranges(std::size_t first, std::size_t n) const {
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::string_view s = tokens_[first + i];
      if (!parse(s, r[i]) || r[i] < 0)
        fail(fmt::format("field 'range of beam {}': expected a finite number >= 0 [m], got '{}'", i,
                         printable(s)));
    }
    return r;
  }

  /// Fields first .. first + n - 1 as finite numbers (read to be checked, not kept).
  void check_numbers(std::size_t first, std::size_t n, std::string_view what) const {
    double v = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if (!parse(tokens_[first + i], v))
        fail(fmt::format("field '{} {}': expected a finite number, got '{}'", what, i,
                         printable(tokens_[first + i])));
  }

  /// Fields k, k+1, k+2 as a pose; x, y, theta name the fields in messages.
  Pose pose(std::size_t k, std::string_view x, std::string_view y, std::string_view theta) const {
    Pose p;  // read in order, so that the first bad field is the one reported
    p(0) = number(k, x);
    p(1) = number(k + 1, y);
    p(2) = number(k + 2, theta);
    return p;
  }

  /// Requires exactly `expected` fields after the name; `layout` describes them.
  void expect_count(std::size_t expected, std::string_view layout) const {
    if (count() != expected)
      fail(fmt::format("expected {} ({} fields), got {} fields{}", layout, expected, count(),
                       count() < expected ? " (a truncated line?)" : ""));
  }

  /// ipc_timestamp at field k, ipc_hostname (any word) and logger_timestamp after it. Returns
  /// ipc_timestamp.
  double timestamps(std::size_t k) const {
    const double t = number(k, "ipc_timestamp");
    number(k + 2, "logger_timestamp");
    return t;
  }

 private:
  static bool parse(std::string_view s, double& v) {
    const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
    return error == std::errc() && end == s.data() + s.size() && std::isfinite(v);
  }

  std::string_view file_;
  std::size_t line_;
  std::vector<std::string_view> tokens_;
};

bool is_message_name(std::string_view s) {
  for (char c : s)
    if (!((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

/// One laser message as read: the scan (range_max still to be set for the old format) and poses.
struct LaserRecord {
  LaserScan scan;
  Pose laser_pose, robot_pose;
};

/// FLASER / RLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger.
LaserRecord read_old_laser(const Fields& f) {
  if (f.count() < 1) f.fail("expected n, the number of readings, got nothing");
  const auto n = static_cast<std::size_t>(f.integer(1, "n", 1, kMaxReadings));
  f.expect_count(n + 10, fmt::format("n = {} ranges, x y theta odom_x odom_y odom_theta "
                                     "ipc_timestamp ipc_hostname logger_timestamp",
                                     n));
  LaserRecord r;
  r.scan.ranges = f.ranges(2, n);
  r.laser_pose = f.pose(n + 2, "x", "y", "theta");
  r.robot_pose = f.pose(n + 5, "odom_x", "odom_y", "odom_theta");
  r.scan.time = f.timestamps(n + 8);
  r.scan.angle_min = -0.5 * kPi;
  r.scan.angle_increment = carmen_angle_increment(n);
  return r;
}

/// ROBOTLASER1 / ROBOTLASER2 (layout in carmen.hpp).
LaserRecord read_robot_laser(const Fields& f) {
  constexpr std::string_view kHead =
      "laser_type start_angle field_of_view angular_resolution maximum_range accuracy "
      "remission_mode num_readings";
  if (f.count() < 8)
    f.fail(fmt::format("expected {} first, got {} fields (a truncated line?)", kHead, f.count()));
  LaserRecord r;
  f.integer(1, "laser_type", 0, kMaxReadings);
  r.scan.angle_min = f.number(2, "start_angle");
  f.number(3, "field_of_view");
  r.scan.angle_increment = f.number(4, "angular_resolution");
  if (r.scan.angle_increment == 0) f.fail("field 'angular_resolution': expected != 0, got 0");
  r.scan.range_max = f.number(5, "maximum_range");
  if (r.scan.range_max <= 0)
    f.fail(fmt::format("field 'maximum_range': expected > 0 [m], got {}", r.scan.range_max));
  f.number(6, "accuracy");
  f.integer(7, "remission_mode", 0, kMaxReadings);
  const auto n = static_cast<std::size_t>(f.integer(8, "num_readings", 1, kMaxReadings));
  if (f.count() < n + 9)
    f.fail(
        fmt::format("expected num_readings = {} ranges, then num_remissions, got {} fields in "
                    "all (a truncated line?)",
                    n, f.count()));
  r.scan.ranges = f.ranges(9, n);
  const auto m = static_cast<std::size_t>(f.integer(n + 9, "num_remissions", 0, kMaxReadings));
  const std::size_t p = n + m + 10;  // first field after the remissions
  f.expect_count(p + 13,
                 fmt::format("{}, {} ranges, num_remissions, {} remissions, laser_x laser_y "
                             "laser_theta robot_x robot_y robot_theta tv rv forward_safety_dist "
                             "side_safety_dist turn_axis ipc_timestamp ipc_hostname "
                             "logger_timestamp",
                             kHead, n, m));
  f.check_numbers(n + 10, m, "remission");
  r.laser_pose = f.pose(p, "laser_x", "laser_y", "laser_theta");
  r.robot_pose = f.pose(p + 3, "robot_x", "robot_y", "robot_theta");
  constexpr const char* kMotion[] = {"tv", "rv", "forward_safety_dist", "side_safety_dist",
                                     "turn_axis"};
  for (std::size_t k = 0; k < 5; ++k) f.number(p + 6 + k, kMotion[k]);
  r.scan.time = f.timestamps(p + 11);
  return r;
}

/// ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp.
CarmenLog::Odometry read_odometry(const Fields& f) {
  f.expect_count(9, "x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp");
  CarmenLog::Odometry o;
  o.pose = f.pose(1, "x", "y", "theta");
  o.tv = f.number(4, "tv");
  o.rv = f.number(5, "rv");
  f.number(6, "accel");
  o.time = f.timestamps(7);
  return o;
}

/// The automatic no-return threshold of old-format scans (rule in carmen.hpp), from the
/// largest reading m of the log's kept FLASER/RLASER scans.
double automatic_range_max(double m) {
  constexpr double kSickMode80 = 80.0, kSaturatedAtLeast = 50.0;
  if (m >= kSickMode80 || m < kSaturatedAtLeast) return kSickMode80;
  return m;
}

}  // namespace

void CarmenOptions::validate() const {
  require(std::isfinite(range_max) && range_max >= 0,
          "CARMEN range_max: expected a finite value >= 0 [m] (0: automatic), got {}", range_max);
}

double carmen_angle_increment(std::size_t beams) {
  if (beams == 180 || beams == 181) return kPi / 180.0;
  if (beams == 360 || beams == 361) return kPi / 360.0;
  if (beams <= 1) return kPi;
  return kPi / static_cast<double>(beams - 1);
}

CarmenLog parse_carmen(std::string_view text, std::string_view name, const CarmenOptions& options) {
  options.validate();
  CarmenLog log;
  log.source = std::string(name);
  std::vector<bool> old_format;  // per scan: range_max from the automatic rule
  double largest_old_reading = 0.0;
  std::size_t line = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const Fields f(name, ++line, text.substr(pos, end - pos));
    pos = end + 1;
    if (f.empty() || f.kind().front() == '#') continue;
    const std::string_view kind = f.kind();
    if (!is_message_name(kind))
      f.fail_line(fmt::format(
          "expected a CARMEN message name (upper-case letters, digits, '_') first, got '{}'",
          printable(kind, 40)));
    const bool old_laser = kind == "FLASER" || kind == "RLASER";
    const bool new_laser = kind == "ROBOTLASER1" || kind == "ROBOTLASER2";
    const bool rear = kind == "RLASER" || kind == "ROBOTLASER2";
    if (kind == "ODOM") {
      log.odometry.push_back(read_odometry(f));
    } else if ((old_laser || new_laser) && (!rear || options.rear_laser)) {
      LaserRecord r = old_laser ? read_old_laser(f) : read_robot_laser(f);
      if (old_laser)
        for (double range : r.scan.ranges)
          largest_old_reading = std::max(largest_old_reading, range);
      log.scans.push_back(std::move(r.scan));
      log.laser_poses.push_back(r.laser_pose);
      log.odometry_poses.push_back(r.robot_pose);
      log.scan_lines.push_back(f.line());
      log.rear.push_back(rear);
      old_format.push_back(old_laser);
    } else {
      ++log.skipped_lines;
    }
  }
  log.lines = line;
  if (log.scans.empty())
    throw ParseError(fmt::format(
        "{}: expected at least one laser scan (a FLASER or ROBOTLASER1 message{}), got none in {} "
        "lines ({} lines of other messages skipped)",
        name, options.rear_laser ? ", or RLASER, ROBOTLASER2" : "", log.lines, log.skipped_lines));
  const double automatic = automatic_range_max(largest_old_reading);
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    LaserScan& scan = log.scans[k];
    if (options.range_max > 0)
      scan.range_max = options.range_max;
    else if (old_format[k])
      scan.range_max = automatic;
    scan.validate(fmt::format("{}:{}", name, log.scan_lines[k]));
  }
  return log;
}

CarmenLog read_carmen(const std::filesystem::path& file, const CarmenOptions& options) {
  const std::string text = read_text_file(file);  // plain or gzip
  return parse_carmen(text, resolve_data_file(file).string(), options);
}

}  // namespace implicit::robot
