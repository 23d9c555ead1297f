// `implicit simulate --map`: a robot drives a tour of a map's free space, turning on the spot at
// each waypoint and driving straight between them, and a laser ray-cast on the map scans at fixed
// time steps. With --format robot-log the log is a robot log (log_format.hpp: map, laser_mount,
// odometry with the alpha noise, laser with "no return" as inf, truth). Otherwise it is CARMEN's
// old format, as read_carmen reads it (carmen.hpp):
//
//   FLASER n r_1 ... r_n x y theta x y theta t implicit t     the true pose as laser and odometry
//   ODOM x y theta tv rv 0 t implicit t                       the same pose, with its speeds
//
// Beam i points at -90 deg + i * carmen_angle_increment(n) (n beams over 180 deg; 180 beams span
// -90 .. +89 deg), the angles every CARMEN reader assumes for FLASER lines. "No return" is
// written as 80 m: with --range-max at most 50 m every hit is below 50 m, so the reader's
// automatic rule reads exactly the 80 m beams as no return (range_max 80 m), and a log without
// any no-return beam has none.
#include "cmd_simulate_laser.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>
#include <sstream>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/map_io.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/scan_simulation.hpp"
#include "laser_tour.hpp"

namespace implicit::app {
namespace {

constexpr double kNoReturn = 80.0;  // [m] read as no return (header comment)
// The log is built in memory: 10^7 readings are about 200 MB of text, far more than a tour
// needs (the bundled Freiburg log has 1.7 million), so a larger count is a wrong flag.
constexpr double kMaxReadings = 1e7;

/// The robot's motion along a path: turns on the spot, then straight drives, one after another.
class Motion {
 public:
  Motion(const std::vector<Vec<2>>& path, double speed, double turn_rate) {
    double h = 0.0, t = 0.0;
    bool first = true;
    for (std::size_t i = 1; i < path.size(); ++i) {
      const Vec<2> d = path[i] - path[i - 1];
      if (d.norm() == 0.0) continue;  // a repeated point: nothing to drive
      const double heading = std::atan2(d.y(), d.x());
      // The robot starts facing its first segment; later it turns the short way round.
      const double turn = first ? 0.0 : wrap_angle(heading - h);
      if (first) h = heading;
      first = false;
      if (turn != 0.0) {
        pieces_.push_back({t, t + std::abs(turn) / turn_rate, path[i - 1], path[i - 1], h, h + turn,
                           std::copysign(turn_rate, turn), 0.0});
        t = pieces_.back().t1;
        h += turn;
      }
      pieces_.push_back({t, t + d.norm() / speed, path[i - 1], path[i], h, h, 0.0, speed});
      t = pieces_.back().t1;
      length_ += d.norm();
    }
  }

  bool empty() const { return pieces_.empty(); }
  double duration() const { return pieces_.empty() ? 0.0 : pieces_.back().t1; }
  double length() const { return length_; }

  /// The pose at time t in [0, duration()] (heading not wrapped), and the speeds then.
  robot::Pose pose(double t, double& tv, double& rv) const {
    auto it = std::lower_bound(pieces_.begin(), pieces_.end(), t,
                               [](const Piece& p, double time) { return p.t1 < time; });
    if (it == pieces_.end()) --it;
    const double f = std::clamp((t - it->t0) / (it->t1 - it->t0), 0.0, 1.0);
    const Vec<2> p = it->from + f * (it->to - it->from);
    tv = it->tv;
    rv = it->rv;
    return {p.x(), p.y(), it->h0 + f * (it->h1 - it->h0)};
  }

 private:
  struct Piece {
    double t0, t1;
    Vec<2> from, to;
    double h0, h1;
    double rv, tv;
  };
  std::vector<Piece> pieces_;
  double length_ = 0.0;
};

std::string point_text(const Vec<2>& p) { return fmt::format("({:.3f}, {:.3f})", p.x(), p.y()); }

/// Why the robot may not stand at p, for messages.
std::string why_blocked(const FreeSpace& space, const Vec<2>& p) {
  const robot::OccupancyGrid& map = space.map();
  const Eigen::Vector2i c = map.cell_of(p);
  if (!map.contains(c(0), c(1))) return "outside the map";
  if (!map.is_free(c(0), c(1)))
    return fmt::format("in cell ({}, {}) of value {}, not free", c(0), c(1), map.at(c(0), c(1)));
  return fmt::format("{:.3f} m from a cell that is not free or the border", space.room(p));
}

/// The user's waypoints, checked: every point and every segment (and the way back to the first
/// point between laps) in the free space.
std::vector<Vec<2>> checked_waypoints(const LaserSimulationCommand& c, const FreeSpace& space) {
  const std::vector<Vec<2>> w = parse_waypoints(c.waypoints);
  const std::string where = fmt::format(
      "in the free space of {} (free cells {} m (--clearance) from occupied and unknown cells and "
      "the border)",
      c.map, c.clearance);
  for (std::size_t i = 0; i < w.size(); ++i)
    require(space.allows(w[i]), "--waypoints: expected point {} {} {}, got it {}", i + 1,
            point_text(w[i]), where, why_blocked(space, w[i]));
  for (std::size_t i = 0; i + 1 < w.size(); ++i)
    if (const auto stop = space.first_blocked(w[i], w[i + 1]))
      throw InvalidArgument(fmt::format(
          "--waypoints: expected the segment from point {} {} to point {} {} {}, got it blocked "
          "at {}: {}",
          i + 1, point_text(w[i]), i + 2, point_text(w[i + 1]), where, point_text(*stop),
          why_blocked(space, *stop)));
  if (c.laps > 1)
    if (const auto stop = space.first_blocked(w.back(), w.front()))
      throw InvalidArgument(fmt::format(
          "--waypoints: expected the way back from the last point {} to the first {} (driven "
          "between --laps) {}, got it blocked at {}: {}",
          point_text(w.back()), point_text(w.front()), where, point_text(*stop),
          why_blocked(space, *stop)));
  return w;
}

robot::OccupancyGrid load_named_map(const std::string& file) {
  try {
    return robot::load_map(file);
  } catch (const ParseError& e) {
    throw ParseError(fmt::format("simulate --map: {}", e.what()));
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(fmt::format("simulate --map: {}", e.what()));
  }
}

/// --odometry-alphas, or 0.02 each (the default of mcl --sensor laser's --alphas).
robot::OdometryAlphas odometry_alphas(const LaserSimulationCommand& c) {
  const std::vector<double>& v = c.odometry_alphas;
  return v.empty() ? robot::OdometryAlphas{0.02, 0.02, 0.02, 0.02}
                   : robot::OdometryAlphas{v[0], v[1], v[2], v[3]};
}

/// What the robot did and what its laser saw: per scan the time, the true pose (heading wrapped),
/// the speeds, and the scan at CARMEN's beam angles with "no return" as +infinity.
struct Tour {
  std::vector<double> times;
  std::vector<robot::Pose> poses;
  std::vector<double> tv, rv;
  std::vector<robot::LaserScan> scans;
  std::size_t hits = 0, no_returns = 0;
};

Tour drive_tour(const LaserSimulationCommand& c, const robot::OccupancyGrid& map,
                const Motion& motion, std::size_t count, bool extra_end, double range_sd,
                std::uint64_t seed) {
  // The simulator's beams are centred on the sensor; turning the sensor by `offset` puts beam i
  // at -90 deg + i * increment, CARMEN's angles (180 beams are not centred).
  const auto n = static_cast<std::size_t>(c.beams);
  const double increment = robot::carmen_angle_increment(n);
  robot::ScanSimulationOptions o;
  o.beams = c.beams;
  o.field_of_view = increment * static_cast<double>(n - 1);
  o.range_max = c.range_max;
  o.range_std = range_sd;
  const robot::LaserMount turned{0.0, 0.0, -0.5 * kPi + 0.5 * o.field_of_view};
  const double half_fov = 0.5 * c.fov_deg * kPi / 180.0;
  Tour tour;
  for (std::size_t k = 0; k < count; ++k) {
    const double t =
        k + 1 == count && extra_end ? motion.duration() : static_cast<double>(k) * c.scan_period;
    double tv = 0.0, rv = 0.0;
    robot::Pose x = motion.pose(t, tv, rv);
    x(2) = wrap_angle(x(2));
    Rng rng({seed, k, 0, purpose::kData});
    robot::LaserScan scan = robot::simulate_scan(map, x, turned, o, rng);
    scan.time = t;
    scan.angle_min = -0.5 * kPi;
    scan.angle_increment = increment;
    scan.range_min = 0.0;
    scan.range_max = c.range_max;
    for (std::size_t i = 0; i < n; ++i) {
      const bool hit =
          scan.ranges[i] < c.range_max && std::abs(scan.bearing(i)) <= half_fov + 1e-12;
      tour.hits += hit ? 1 : 0;
      tour.no_returns += hit ? 0 : 1;
      if (!hit) scan.ranges[i] = std::numeric_limits<double>::infinity();
    }
    tour.times.push_back(t);
    tour.poses.push_back(x);
    tour.tv.push_back(tv);
    tour.rv.push_back(rv);
    tour.scans.push_back(std::move(scan));
  }
  return tour;
}

/// CARMEN's old format (the header comment of this file).
std::string carmen_text(const LaserSimulationCommand& c, const Tour& tour,
                        const std::vector<Vec<2>>& w, double range_sd, std::uint64_t seed) {
  const std::size_t n = tour.scans.front().size();
  const double increment = tour.scans.front().angle_increment;
  std::string text = fmt::format(
      "# CARMEN laser log written by implicit simulate --map (docs/cli.md)\n"
      "# map {}, seed {}, {} beams from -90 deg {} deg apart, field of view {} deg, range_max {} "
      "m, range sd {} m; no return is written as {} m\n"
      "# each FLASER line carries the true pose as laser and odometry pose; an ODOM line follows\n"
      "# waypoints",
      c.map, seed, n, increment * 180.0 / kPi, c.fov_deg, c.range_max, range_sd, kNoReturn);
  for (std::size_t i = 0; i < w.size(); ++i)
    text += fmt::format("{}{},{}", i ? ";" : " ", w[i].x(), w[i].y());
  text += "\n";
  auto out = std::back_inserter(text);
  for (std::size_t k = 0; k < tour.scans.size(); ++k) {
    fmt::format_to(out, "FLASER {}", n);
    for (double r : tour.scans[k].ranges) fmt::format_to(out, " {}", std::isinf(r) ? kNoReturn : r);
    const robot::Pose& x = tour.poses[k];
    const double t = tour.times[k];
    fmt::format_to(out, " {} {} {} {} {} {} {} implicit {}\n", x(0), x(1), x(2), x(0), x(1), x(2),
                   t, t);
    fmt::format_to(out, "ODOM {} {} {} {} {} 0 {} implicit {}\n", x(0), x(1), x(2), tour.tv[k],
                   tour.rv[k], t, t);
  }
  return text;
}

/// The map as a `map` record: its path from the log's folder, one word.
std::string map_record_path(const std::string& map, const std::filesystem::path& log) {
  const std::filesystem::path folder = std::filesystem::absolute(log).parent_path();
  const std::string relative =
      std::filesystem::absolute(map).lexically_normal().lexically_proximate(folder).string();
  require(relative.find_first_of(" \t#") == std::string::npos,
          "simulate --format robot-log: expected a --map path without blanks or '#' (the log's "
          "'map' record holds one word), got '{}'",
          relative);
  return relative;
}

/// The robot log: the map, the scans, the truth and the odometry the robot would have reported,
/// each increment perturbed by the alpha noise (stream (seed, k, 1, data) for the step to scan
/// k), integrated from the origin of the odometry's own frame.
std::string robot_log_text(const LaserSimulationCommand& c, const Tour& tour,
                           const std::string& map_record, double range_sd, std::uint64_t seed) {
  const robot::OdometryAlphas a = odometry_alphas(c);
  robot::RobotLog log;
  log.map = robot::MapReference{map_record, 0};
  log.laser_mount = robot::LaserMount{};
  robot::Pose odometry = robot::Pose::Zero();
  for (std::size_t k = 0; k < tour.scans.size(); ++k) {
    if (k > 0) {
      Rng rng({seed, k, 1, purpose::kData});
      const robot::Pose step = robot::between(tour.poses[k - 1], tour.poses[k]);
      odometry = robot::compose(odometry, robot::perturb_odometry(step, a, rng));
      odometry(2) = wrap_angle(odometry(2));
    }
    log.odometry.push_back({tour.times[k], odometry});
    log.truth.push_back({tour.times[k], tour.poses[k].head<2>(), tour.poses[k](2)});
  }
  log.laser_scans = tour.scans;
  std::ostringstream text;
  text << fmt::format(
      "# robot log written by implicit simulate --map --format robot-log (docs/cli.md)\n"
      "# map {}, seed {}, field of view {} deg, range sd {} m, odometry alphas {} {} {} {}\n",
      c.map, seed, c.fov_deg, range_sd, a.alpha1, a.alpha2, a.alpha3, a.alpha4);
  robot::write_robot_log(text, log);
  return text.str();
}

}  // namespace

CLI::Option* add_laser_simulation_options(CLI::App& sub, LaserSimulationCommand& c) {
  CLI::Option* map = sub.add_option(
      "--map", c.map,
      "Laser mode: a map_server YAML map; simulate a robot touring its free space with a laser "
      "and write a CARMEN log or a robot log (--format; for mcl --sensor laser)");
  const auto laser = [&](CLI::Option* o) { o->needs(map)->capture_default_str(); };
  sub.add_option("--waypoints", c.waypoints,
                 "--map: the path 'x1,y1;x2,y2;...' [m], driven in order (default: a closed tour "
                 "found on the map)")
      ->needs(map)
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            // Malformed text is a usage error (exit 2), found before the map is read; CLI11
            // puts the flag's name in front of the message itself.
            try {
              parse_waypoints(text);
              return {};
            } catch (const InvalidArgument& e) {
              const std::string_view m = e.what(), prefix = "--waypoints: ";
              return std::string(m.substr(m.rfind(prefix, 0) == 0 ? prefix.size() : 0));
            }
          },
          "X,Y;X,Y;..."));
  laser(sub.add_option("--speed", c.speed, "--map: [m/s] driving speed")
            ->check(in_range(0.01, 10.0)));
  laser(sub.add_option("--turn-rate", c.turn_rate_deg, "--map: [deg/s] turning on the spot")
            ->check(in_range(1.0, 720.0)));
  laser(sub.add_option("--scan-period", c.scan_period, "--map: [s] between scans")
            ->check(in_range(0.001, 60.0)));
  laser(sub.add_option("--clearance", c.clearance,
                       "--map: [m] the path keeps this far from occupied and unknown cells")
            ->check(in_range(0.0, 10.0)));
  laser(sub.add_option("--laps", c.laps, "--map: times round the path")->check(in_range(1, 1000)));
  laser(sub.add_option("--beams", c.beams,
                       "--map: beams over 180 deg from -90 deg, as CARMEN reads FLASER lines "
                       "(180: 1 deg apart to +89; 181: to +90; 361: 0.5 deg)")
            ->check(in_range(2, 10000)));
  laser(sub.add_option("--fov-deg", c.fov_deg,
                       "--map: [deg] field of view, centred; beams outside read no return")
            ->check(in_range(1.0, 180.0)));
  laser(sub.add_option("--range-max", c.range_max,
                       "--map: [m] the laser's range (at most 50: no return is written as 80 m)")
            ->check(in_range(0.1, 50.0)));
  laser(sub.add_option("--format", c.format,
                       "--map: the log's format: carmen (FLASER and ODOM lines, the true pose as "
                       "odometry) or robot-log (docs/formats.md: map, laser, noisy odometry and "
                       "truth records)")
            ->check(CLI::IsMember({"carmen", "robot-log"})));
  sub.add_option("--odometry-alphas", c.odometry_alphas,
                 "--format robot-log: alpha1..alpha4 of the odometry's noise (nav2's names; "
                 "default 0.02 each)")
      ->needs(map)
      ->expected(4)
      ->check(in_range(0.0, 10.0));
  return map;
}

void run_laser_simulation(const LaserSimulationCommand& c, double range_sd, const RunContext& ctx) {
  require(c.format == "robot-log" || c.odometry_alphas.empty(),
          "simulate --odometry-alphas: the CARMEN log records the true pose as odometry; noisy "
          "odometry needs --format robot-log");
  const bool robot_log = c.format == "robot-log";
  const std::string map_record = robot_log ? map_record_path(c.map, ctx.out_dir) : "";
  const robot::OccupancyGrid map = load_named_map(c.map);
  const FreeSpace space(map, c.clearance);
  const std::vector<Vec<2>> w = c.waypoints.empty()
                                    ? automatic_tour(space, "simulate --map " + c.map)
                                    : checked_waypoints(c, space);
  std::vector<Vec<2>> path;
  for (int lap = 0; lap < c.laps; ++lap) path.insert(path.end(), w.begin(), w.end());
  const Motion motion(path, c.speed, c.turn_rate_deg * kPi / 180.0);
  require(!motion.empty(), "--waypoints: expected points that span a path, got all at {}",
          point_text(w.front()));
  const double scans_on_grid = std::floor(motion.duration() / c.scan_period + 1e-9);
  const double last_on_grid = scans_on_grid * c.scan_period;
  const bool extra_end = motion.duration() - last_on_grid > 1e-9 * std::max(1.0, last_on_grid);
  const double scans = scans_on_grid + 1.0 + (extra_end ? 1.0 : 0.0);
  require(scans * c.beams <= kMaxReadings,
          "simulate --map: expected at most {:.0f} readings (scans x --beams), got {:.0f} scans "
          "x {} beams (the tour takes {:.1f} s at --speed {} m/s, a scan every --scan-period {} "
          "s); raise --scan-period, or lower --laps or --beams",
          kMaxReadings, scans, c.beams, motion.duration(), c.speed, c.scan_period);
  const auto count = static_cast<std::size_t>(scans);
  const Tour tour = drive_tour(c, map, motion, count, extra_end, range_sd, ctx.seed);
  // Under a temporary name, renamed when complete; gzip for a name ending in .gz (read_carmen
  // detects it).
  write_output_file(ctx.out_dir, robot_log ? robot_log_text(c, tour, map_record, range_sd, ctx.seed)
                                           : carmen_text(c, tour, w, range_sd, ctx.seed));
  const auto n = static_cast<std::size_t>(c.beams);
  const double increment = tour.scans.front().angle_increment;
  const std::size_t hits = tour.hits, no_return = tour.no_returns;

  nlohmann::json waypoints = nlohmann::json::array();
  for (const Vec<2>& p : w) waypoints.push_back({p.x(), p.y()});
  const nlohmann::json j{
      {"file", ctx.out_dir.string()},
      {"map", c.map},
      {"format", c.format},
      {"seed", ctx.seed},
      {"scans", count},
      {"beams", n},
      {"beam_spacing_deg", increment * 180.0 / kPi},
      {"fov_deg", c.fov_deg},
      {"range_max_m", c.range_max},
      {"range_sd_m", range_sd},
      {"no_return_reading_m",
       c.format == "carmen" ? nlohmann::json(kNoReturn) : nlohmann::json(nullptr)},  // inf
      {"hits", hits},
      {"no_returns", no_return},
      {"speed_m_s", c.speed},
      {"turn_rate_deg_s", c.turn_rate_deg},
      {"scan_period_s", c.scan_period},
      {"clearance_m", c.clearance},
      {"laps", c.laps},
      {"waypoints_from", c.waypoints.empty() ? "automatic" : "--waypoints"},
      {"waypoints", waypoints},
      {"path_length_m", motion.length()},
      {"seconds_simulated", motion.duration()}};
  if (ctx.json) {
    print_json(j);
    return;
  }
  fmt::print(
      "{}: {} scans of {} beams over {:.1f} s, {:.1f} m along {} waypoints ({}) on {}; {} hits, "
      "{} no returns\n",
      ctx.out_dir.string(), count, n, motion.duration(), motion.length(), w.size(),
      c.waypoints.empty() ? "automatic" : "--waypoints", c.map, hits, no_return);
}

}  // namespace implicit::app
