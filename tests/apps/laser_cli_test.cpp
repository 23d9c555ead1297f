// `implicit map` and `implicit simulate --map`: the map of a CARMEN log against closed forms and
// the library's mapper; the simulated log against the motion's closed form and cast_ray on the
// map; the simulated log localized by `implicit mcl --sensor laser`, in both formats (CARMEN and
// the robot log with its own odometry); and the documented robot log of a laser run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/map_io.hpp"

namespace {

using implicit::kPi;
using implicit::Vec;
using implicit::robot::OccupancyGrid;
using implicit::robot::Pose;
using implicit::test::run_cli;
using implicit::test::TempDir;
namespace fs = std::filesystem;
namespace robot = implicit::robot;

// ---- map ------------------------------------------------------------------------------------

// The robot stands at the centre of a cell, (0.025, 0.025), in a square room whose walls are
// 2 m away on all four sides: a beam at world angle a reads 2 / max(|cos a|, |sin a|), and the
// walls x = 2.025, x = -1.975, ... run through the middle of cells of the 5 cm map (no beam end
// on a cell border). Each scan is written `repeats` times at headings 0 and pi, so that the 181
// beams of 1 deg see the whole circle. `odometry` is the robot pose written beside each laser
// pose: equal to it, or offset by a mount.
constexpr double kRobotXY = 0.025, kWall = 2.0, kResolution = 0.05;

std::string room_log(int repeats, const Pose& mount) {
  std::string text = "# a square room\n";
  for (int k = 0; k < repeats; ++k)
    for (double heading : {0.0, kPi}) {
      const Pose laser(kRobotXY, kRobotXY, heading);
      const Pose odometry = robot::compose(laser, robot::between(mount, Pose::Zero()));
      text += "FLASER 181";
      for (int i = 0; i < 181; ++i) {
        const double a = heading - 0.5 * kPi + i * kPi / 180.0;
        text += fmt::format(" {}", kWall / std::max(std::abs(std::cos(a)), std::abs(std::sin(a))));
      }
      text += fmt::format(" {} {} {} {} {} {} {} host {}\n", laser(0), laser(1), laser(2),
                          odometry(0), odometry(1), odometry(2), k, k);
    }
  return text;
}

bool occupied_at(const OccupancyGrid& g, double x, double y) {
  const Eigen::Vector2i c = g.cell_of(Vec<2>(x, y));
  return g.contains(c(0), c(1)) && g.is_occupied(c(0), c(1));
}

// What the room must give whatever the mapper's details: walls where the four perpendicular beams
// end (hit by them alone: the neighbouring beams, 1 deg off, end in the next cells and cross no
// other cell of the wall's column or row); free cells near the robot (each cell within 1 m spans
// more than 2.8 deg, so at least 2 of the 1-deg beams cross it per pass, 6 misses in 3 passes:
// log-odds -2.4, p = 0.08, below the free threshold 0.196); nothing occupied inside the room.
void expect_room(const OccupancyGrid& g) {
  const double c = kRobotXY;
  EXPECT_TRUE(occupied_at(g, c + kWall, c));
  EXPECT_TRUE(occupied_at(g, c - kWall, c));
  EXPECT_TRUE(occupied_at(g, c, c + kWall));
  EXPECT_TRUE(occupied_at(g, c, c - kWall));
  int free_checked = 0;
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      const Vec<2> d = g.cell_center(ix, iy) - Vec<2>(c, c);
      if (d.norm() >= 0.1 && d.norm() <= 1.0) {
        EXPECT_TRUE(g.is_free(ix, iy)) << ix << " " << iy;
        ++free_checked;
      }
      if (std::abs(d.x()) < kWall - kResolution && std::abs(d.y()) < kWall - kResolution) {
        EXPECT_FALSE(g.is_occupied(ix, iy)) << ix << " " << iy;
      }
    }
  EXPECT_GT(free_checked, 1000);  // pi (1^2 - 0.1^2) / 0.05^2 = 1244 cells
}

TEST(MapCli, SquareRoomGivesItsWallsAndTheLibrarysMap) {
  TempDir dir("map_room");
  const auto log = dir.path() / "room.log";
  implicit::test::write_file(log, room_log(3, Pose::Zero()));
  const auto yaml = dir.path() / "room.yaml";
  const auto r = run_cli("map --json --data '" + log.string() + "' --out '" + yaml.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const OccupancyGrid g = robot::load_map(yaml);
  expect_room(g);

  // The same map from the library's mapper, on the log as read (the mount is zero).
  const robot::CarmenLog parsed = robot::read_carmen(log);
  robot::GridMappingOptions o;
  o.resolution = kResolution;
  o.max_range = 40.0;
  const OccupancyGrid expected = robot::build_map(parsed.laser_poses, parsed.scans, {}, o);
  ASSERT_EQ(g.width(), expected.width());
  ASSERT_EQ(g.height(), expected.height());
  EXPECT_EQ(g.origin(), expected.origin());
  long occupied = 0, free = 0, unknown = 0;
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      EXPECT_EQ(g.is_occupied(ix, iy), expected.is_occupied(ix, iy)) << ix << " " << iy;
      EXPECT_EQ(g.is_free(ix, iy), expected.is_free(ix, iy)) << ix << " " << iy;
      occupied += g.is_occupied(ix, iy);
      free += g.is_free(ix, iy);
      unknown += !g.is_occupied(ix, iy) && !g.is_free(ix, iy);
    }
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["occupied"], occupied);
  EXPECT_EQ(j["free"], free);
  EXPECT_EQ(j["unknown"], unknown);
  EXPECT_EQ(j["cells"], g.width() * g.height());
  EXPECT_DOUBLE_EQ(j["width_m"].get<double>(), g.width() * kResolution);
  EXPECT_EQ(j["scans"], 6);
  // Written under temporary names and renamed: only the two files are left.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir.path())) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"room.log", "room.pgm", "room.yaml"}));
}

// A laser mounted ahead of the robot: the log's odometry poses are the robot's, and the map must
// still be drawn from the laser's poses. A mount applied the wrong way, or not at all, would move
// every wall by 0.2 m (4 cells) and turn it by 0.3 rad.
TEST(MapCli, TheMountIsTakenOffTheLaserPoses) {
  TempDir dir("map_mount");
  const auto log = dir.path() / "mounted.log";
  const Pose mount(0.2, -0.1, 0.3);
  implicit::test::write_file(log, room_log(3, mount));
  const auto yaml = dir.path() / "mounted.yaml";
  const auto r = run_cli("map --json --data '" + log.string() + "' --out '" + yaml.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_room(robot::load_map(yaml));
  const auto j = nlohmann::json::parse(r.out);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(j["mount"][k].get<double>(), mount(k), 1e-12) << k;
}

TEST(MapCli, BundledAcesLogGivesTheLibrarysMap) {
  TempDir dir("map_aces");
  const fs::path log = fs::path(IMPLICIT_SOURCE_DIR) / "data/carmen/aces-corrected.log.gz";
  const auto yaml = dir.path() / "aces.yaml";
  const auto r = run_cli("map --data '" + log.string() + "' --out '" + yaml.string() +
                         "' --resolution 0.1 --max-range 30");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(yaml.string() + ": "), std::string::npos) << r.out;
  const OccupancyGrid g = robot::load_map(yaml);
  const robot::CarmenLog parsed = robot::read_carmen(log);
  robot::GridMappingOptions o;
  o.resolution = 0.1;
  o.max_range = 30.0;
  const OccupancyGrid expected = robot::build_map(parsed.laser_poses, parsed.scans, {}, o);
  ASSERT_EQ(g.width(), expected.width());
  ASSERT_EQ(g.height(), expected.height());
  long differ = 0, occupied = 0;
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      differ += g.is_occupied(ix, iy) != expected.is_occupied(ix, iy) ||
                g.is_free(ix, iy) != expected.is_free(ix, iy);
      occupied += g.is_occupied(ix, iy);
    }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(occupied, 1000);  // a building's walls, not an empty grid
}

// ---- simulate --map -------------------------------------------------------------------------

// An 8 m x 6 m room, x in [-1, 7), y in [-1, 5), walled by its border cells, with a 1 m pillar
// at x in [2.5, 3.5), y in [1.5, 2.5).
fs::path write_room_map(const TempDir& dir) {
  OccupancyGrid g(160, 120, kResolution, Vec<2>(-1.0, -1.0), OccupancyGrid::kFree);
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      const Vec<2> p = g.cell_center(ix, iy);
      const bool border = ix == 0 || iy == 0 || ix == g.width() - 1 || iy == g.height() - 1;
      const bool pillar = p.x() > 2.5 && p.x() < 3.5 && p.y() > 1.5 && p.y() < 2.5;
      if (border || pillar) g.at(ix, iy) = OccupancyGrid::kOccupied;
    }
  const fs::path yaml = dir.path() / "room.yaml";
  robot::save_map(g, yaml);
  return yaml;
}

// The waypoints of the tests below, off the cell borders (a pose on a cell corner would send
// beams exactly through cell corners, where a rounding of the beam angle decides the cell).
// Speed 1 m/s, 90 deg/s: along x for 6 s, a quarter turn in 1 s, along y for 4 s; a scan every
// 0.25 s gives 45 scans, the last at 11 s on the last waypoint.
constexpr const char* kWaypoints = "0.01,0.013;6.01,0.013;6.01,4.013";
constexpr const char* kMotion = " --speed 1 --turn-rate 90 --scan-period 0.25";

/// The pose at time t of that motion, in closed form.
Pose expected_pose(double t) {
  if (t <= 6.0) return {0.01 + t, 0.013, 0.0};
  if (t <= 7.0) return {6.01, 0.013, (t - 6.0) * 0.5 * kPi};
  return {6.01, 0.013 + (t - 7.0), 0.5 * kPi};
}

TEST(SimulateLaserCli, WaypointLogFollowsTheMotionAndCastRay) {
  TempDir dir("simulate_laser_waypoints");
  const fs::path yaml = write_room_map(dir);
  const OccupancyGrid map = robot::load_map(yaml);
  // 180 beams span -90 .. +89 deg, 181 and 361 -90 .. +90 deg, any other count 180 deg in
  // equal steps (carmen_angle_increment); with --fov-deg 90 only beams within +-45 deg return.
  struct Case {
    int beams;
    double fov_deg, increment;
  };
  for (const Case& c :
       {Case{180, 180, kPi / 180}, Case{181, 180, kPi / 180}, Case{361, 180, kPi / 360},
        Case{90, 180, kPi / 89}, Case{181, 90, kPi / 180}}) {
    SCOPED_TRACE(fmt::format("{} beams, fov {} deg", c.beams, c.fov_deg));
    const fs::path log = dir.path() / fmt::format("sim_{}_{}.log", c.beams, c.fov_deg);
    const auto r = run_cli(fmt::format(
        "simulate --json --map '{}' --out '{}' --waypoints '{}'{} --range-sd 0 --beams {} "
        "--fov-deg {}",
        yaml.string(), log.string(), kWaypoints, kMotion, c.beams, c.fov_deg));
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const robot::CarmenLog s = robot::read_carmen(log);
    ASSERT_EQ(s.scans.size(), 45u);
    EXPECT_EQ(j["scans"], 45);
    ASSERT_EQ(s.odometry.size(), 45u);
    EXPECT_DOUBLE_EQ(j["seconds_simulated"].get<double>(), 11.0);
    EXPECT_DOUBLE_EQ(j["path_length_m"].get<double>(), 10.0);
    for (std::size_t k = 0; k < s.scans.size(); ++k) {
      const double t = 0.25 * static_cast<double>(k);
      const Pose truth = expected_pose(t);
      const Pose& p = s.laser_poses[k];
      EXPECT_DOUBLE_EQ(s.scans[k].time, t) << k;
      EXPECT_EQ(s.odometry_poses[k], p) << k;
      EXPECT_EQ(s.odometry[k].pose, p) << k;
      EXPECT_EQ(s.odometry[k].time, t) << k;
      // Rounding of t * speed and of the heading's interpolation only.
      EXPECT_NEAR(p(0), truth(0), 1e-9) << k;
      EXPECT_NEAR(p(1), truth(1), 1e-9) << k;
      EXPECT_NEAR(implicit::wrap_angle(p(2) - truth(2)), 0.0, 1e-9) << k;
      ASSERT_EQ(s.scans[k].size(), static_cast<std::size_t>(c.beams));
      EXPECT_DOUBLE_EQ(s.scans[k].angle_min, -0.5 * kPi);
      EXPECT_DOUBLE_EQ(s.scans[k].angle_increment, c.increment);
      for (std::size_t i = 0; i < s.scans[k].size(); ++i) {
        const double bearing = -0.5 * kPi + static_cast<double>(i) * c.increment;
        if (std::abs(bearing) > 0.5 * c.fov_deg * kPi / 180.0 + 1e-12) {
          EXPECT_FALSE(s.scans[k].is_hit(i)) << k << " " << i;
          continue;
        }
        // The simulator turns its centred beams onto CARMEN's angles, so its angle may differ
        // from this one by a few ulps (1e-15 rad): a range difference of r 1e-15 / sin(incidence),
        // far below 1e-6 m unless a beam grazes a wall within 1e-9 rad.
        const double expected = robot::cast_ray(map, p.head<2>(), p(2) + bearing, 30.0);
        ASSERT_LT(expected, 30.0);  // the room is closed
        EXPECT_TRUE(s.scans[k].is_hit(i)) << k << " " << i;
        EXPECT_NEAR(s.scans[k].ranges[i], expected, 1e-6) << k << " " << i;
      }
    }
  }
}

TEST(SimulateLaserCli, RangeNoiseHasTheGivenSd) {
  TempDir dir("simulate_laser_noise");
  const fs::path yaml = write_room_map(dir);
  const OccupancyGrid map = robot::load_map(yaml);
  const fs::path log = dir.path() / "noisy.log";
  const double sd = 0.05;
  const auto r =
      run_cli(fmt::format("simulate --map '{}' --out '{}' --waypoints '{}'{} --range-sd {}",
                          yaml.string(), log.string(), kWaypoints, kMotion, sd));
  ASSERT_EQ(r.code, 0) << r.err;
  const robot::CarmenLog s = robot::read_carmen(log);
  double sum = 0.0, sum2 = 0.0;
  long n = 0;
  for (std::size_t k = 0; k < s.scans.size(); ++k)
    for (std::size_t i = 0; i < s.scans[k].size(); ++i) {
      const Pose& p = s.laser_poses[k];
      const double e = s.scans[k].ranges[i] -
                       robot::cast_ray(map, p.head<2>(), p(2) + s.scans[k].bearing(i), 30.0);
      sum += e;
      sum2 += e * e;
      ++n;
    }
  ASSERT_EQ(n, 45 * 181);
  // Every beam hits within 10 m, so no reading is clamped (to [0.05, 30) m): the errors are
  // N(0, sd^2). Their mean has standard error sd / sqrt(n), their sample sd a relative standard
  // error of 1 / sqrt(2 n); 4.5 standard errors each.
  const double mean = sum / n, rms = std::sqrt(sum2 / n);
  EXPECT_LT(std::abs(mean), 4.5 * sd / std::sqrt(n)) << mean;
  EXPECT_LT(std::abs(rms / sd - 1.0), 4.5 / std::sqrt(2.0 * n)) << rms;
}

/// The centres of the map's cells that are not free.
std::vector<Vec<2>> walls_of(const OccupancyGrid& map) {
  std::vector<Vec<2>> walls;
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix)
      if (!map.is_free(ix, iy)) walls.push_back(map.cell_center(ix, iy));
  return walls;
}

TEST(SimulateLaserCli, AutomaticTourStaysClearAndReturnsToItsStart) {
  TempDir dir("simulate_laser_tour");
  const fs::path yaml = write_room_map(dir);
  const OccupancyGrid map = robot::load_map(yaml);
  const std::vector<Vec<2>> walls = walls_of(map);
  const double clearance = 0.4;
  const std::string args = fmt::format("simulate --json --map '{}' --clearance {} --seed 5 --out ",
                                       yaml.string(), clearance);
  const fs::path log = dir.path() / "tour.log";
  const auto r = run_cli(args + "'" + log.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["waypoints_from"], "automatic");
  EXPECT_GE(j["waypoints"].size(), 3u);  // out and back at least
  const robot::CarmenLog s = robot::read_carmen(log);
  ASSERT_GE(s.scans.size(), 20u);
  EXPECT_EQ(s.scans.size(), j["scans"].get<std::size_t>());
  // The tour is kept `clearance` from the centres of cells that are not free, measured between
  // cell centres and interpolated bilinearly; the exact distance from a point to the nearest such
  // centre is 1-Lipschitz, so it is at most half a cell diagonal below the interpolation.
  const double allowed = clearance - kResolution * std::sqrt(0.5);
  for (std::size_t k = 0; k < s.scans.size(); ++k) {
    const Vec<2> p = s.laser_poses[k].head<2>();
    double nearest = 1e9;
    for (const Vec<2>& w : walls) nearest = std::min(nearest, (w - p).norm());
    EXPECT_GE(nearest, allowed) << "scan " << k << " at " << p.transpose();
    if (k > 0) {  // 0.5 m/s, a scan every 0.2 s
      EXPECT_LE((p - s.laser_poses[k - 1].head<2>()).norm(), 0.1 + 1e-9) << k;
    }
  }
  EXPECT_LT((s.laser_poses.front() - s.laser_poses.back()).head<2>().norm(), 1e-9);
  // The tour depends on the map and the flags only: the same command writes the same file.
  const fs::path again = dir.path() / "again.log";
  ASSERT_EQ(run_cli(args + "'" + again.string() + "'").code, 0);
  EXPECT_EQ(implicit::test::read_file(log), implicit::test::read_file(again));
}

// The bound on the position RMSE of a filter that follows the robot through these scans: the
// likelihood field weighs each used beam by N(d; 0, sigma_hit^2) in its end point's distance d to
// the nearest wall, and a pose off by delta moves the end points on a wall of normal n by
// n . delta, so k used beams on walls facing one axis give the posterior a variance of at most
// sigma_hit^2 / k along it (the prediction only adds information; z_rand only fattens the tails).
// With k_x and k_y counted per scan from the walls the beams hit (faces of cells at x = const
// or y = const, in the proportion max_beams / beams of the used ones), the expected squared
// position error is at most 2 sigma_hit^2 / min(k_x, k_y); the bound is 4.5 times the root of its
// mean over the scans. It holds whatever the scan noise (0.02 m here, far below sigma_hit =
// 0.2 m) and the odometry's, and fails for a filter that loses the robot or reads the beams at
// other angles. `j` is the run's JSON (sigma_hit, max_beams).
double rmse_bound(const OccupancyGrid& map, const std::vector<Pose>& poses,
                  const std::vector<robot::LaserScan>& scans, const nlohmann::json& j) {
  const double sigma_hit = j["laser"]["sigma_hit"].get<double>();
  const double used = j["laser"]["max_beams"].get<double>() / static_cast<double>(scans[0].size());
  double mean_inverse_k = 0.0;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const Pose& p = poses[k];
    int facing_x = 0, facing_y = 0;
    for (std::size_t i = 0; i < scans[k].size(); ++i) {
      const double a = p(2) + scans[k].bearing(i);
      const double range = robot::cast_ray(map, p.head<2>(), a, 30.0);
      const Vec<2> e = (p.head<2>() + range * Vec<2>(std::cos(a), std::sin(a)) - map.origin()) /
                       map.resolution();
      const double off_x = std::abs(e.x() - std::round(e.x()));
      const double off_y = std::abs(e.y() - std::round(e.y()));
      ++(off_x < off_y ? facing_x : facing_y);
    }
    const double k_min = used * std::min(facing_x, facing_y);
    EXPECT_GE(k_min, 1.0) << "scan " << k << " sees walls of one direction only";
    mean_inverse_k += 1.0 / k_min / static_cast<double>(scans.size());
  }
  return 4.5 * std::sqrt(2.0 * sigma_hit * sigma_hit * mean_inverse_k);
}

/// Every run's position RMSE in the JSON `j` (printed by the command as `out`) is below `bound`.
void expect_runs_within(const nlohmann::json& j, double bound, const std::string& out) {
  for (const auto& run : j["per_run"])
    EXPECT_LT(run["position_rmse_m"].get<double>(), bound) << out;
  std::printf("position RMSE %.4f m (bound %.4f m)\n", j["position_rmse_m"]["mean"].get<double>(),
              bound);
}

// The simulated log localized on its own map, within rmse_bound.
TEST(SimulateLaserCli, MclOnTheSimulatedLogFollowsTheRobot) {
  TempDir dir("simulate_laser_mcl");
  const fs::path yaml = write_room_map(dir);
  const OccupancyGrid map = robot::load_map(yaml);
  const fs::path log = dir.path() / "sim.log";
  const auto sim =
      run_cli(fmt::format("simulate --map '{}' --out '{}' --seed 3", yaml.string(), log.string()));
  ASSERT_EQ(sim.code, 0) << sim.err;
  const auto r = run_cli(
      fmt::format("mcl --sensor laser --map '{}' --data '{}' --runs 2 -M 100 --json --quiet",
                  yaml.string(), log.string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GE(j["updates"].get<int>(), 20);
  EXPECT_EQ(j["lost_runs"], 0);
  EXPECT_EQ(j["odometry"], "synthesised");

  const robot::CarmenLog s = robot::read_carmen(log);
  expect_runs_within(j, rmse_bound(map, s.laser_poses, s.scans, j), r.out);
}

// ---- the robot log format (simulate --format robot-log, mcl on it) ---------------------------

// The two formats of one simulation: the same scans (no return: 80 m in CARMEN, inf here), the
// true poses as truth, the map named relative to the log. With zero odometry noise each odometry
// increment is the true one (rounding only), from the odometry frame's origin.
TEST(SimulateLaserCli, RobotLogFormatCarriesTheCarmenLogsScansTruthAndOdometry) {
  TempDir dir("simulate_laser_robot_log");
  const fs::path yaml = write_room_map(dir);
  const std::string args = fmt::format("simulate --json --map '{}' --waypoints '{}'{} --seed 4",
                                       yaml.string(), kWaypoints, kMotion);
  const fs::path carmen = dir.path() / "sim.log", ours = dir.path() / "logs" / "sim.txt";
  fs::create_directories(ours.parent_path());
  ASSERT_EQ(run_cli(args + " --out '" + carmen.string() + "'").code, 0);
  const auto r =
      run_cli(args + " --format robot-log --odometry-alphas 0 0 0 0 --out '" + ours.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["format"], "robot-log");
  const robot::CarmenLog c = robot::read_carmen(carmen);
  const robot::RobotLog log = robot::read_robot_log(ours);
  ASSERT_TRUE(log.map.has_value());
  EXPECT_EQ(log.map->file, "../room.yaml");
  EXPECT_EQ(fs::canonical(robot::map_file(log)), fs::canonical(yaml));
  ASSERT_EQ(log.laser_scans.size(), 45u);
  ASSERT_EQ(log.truth.size(), 45u);
  ASSERT_EQ(log.odometry.size(), 45u);
  EXPECT_EQ(log.odometry[0].pose, Pose::Zero());
  for (std::size_t k = 0; k < 45; ++k) {
    const robot::LaserScan &a = c.scans[k], &b = log.laser_scans[k];
    EXPECT_EQ(b.time, a.time) << k;
    EXPECT_EQ(b.angle_min, a.angle_min) << k;
    EXPECT_EQ(b.angle_increment, a.angle_increment) << k;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(b.is_hit(i), a.is_hit(i)) << k << " " << i;
      // CARMEN's text has the shortest round-trip digits, ours 17: the same double.
      if (a.is_hit(i)) {
        EXPECT_EQ(b.ranges[i], a.ranges[i]) << k << " " << i;
      }
    }
    EXPECT_EQ(log.truth[k].time, a.time);
    EXPECT_EQ(log.truth[k].position, c.laser_poses[k].head<2>()) << k;
    EXPECT_EQ(*log.truth[k].heading, c.laser_poses[k](2)) << k;
    if (k == 0) continue;
    const Pose moved = robot::between(c.laser_poses[k - 1], c.laser_poses[k]);
    const Pose reported = robot::between(log.odometry[k - 1].pose, log.odometry[k].pose);
    for (int m = 0; m < 2; ++m) EXPECT_NEAR(reported(m), moved(m), 1e-12) << k;
    EXPECT_NEAR(implicit::wrap_angle(reported(2) - moved(2)), 0.0, 1e-12) << k;
  }
}

// Localization on the robot log's own odometry (noisy: the default alphas) and map record, with
// no --map: within the bound of the CARMEN run.
TEST(SimulateLaserCli, MclOnTheSimulatedRobotLogUsesItsOdometryAndFollowsTheRobot) {
  TempDir dir("simulate_laser_robot_log_mcl");
  const fs::path yaml = write_room_map(dir);
  const OccupancyGrid map = robot::load_map(yaml);
  const fs::path log = dir.path() / "sim.txt";
  const auto sim = run_cli(fmt::format("simulate --map '{}' --format robot-log --out '{}' --seed 3",
                                       yaml.string(), log.string()));
  ASSERT_EQ(sim.code, 0) << sim.err;
  const auto r = run_cli(
      fmt::format("mcl --sensor laser --data '{}' --runs 2 -M 100 --json --quiet", log.string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["odometry"], "recorded");
  EXPECT_TRUE(j["odometry_noise"].is_null());
  EXPECT_GE(j["updates"].get<int>(), 20);
  EXPECT_EQ(j["scored_updates"], 2 * j["updates"].get<int>());
  EXPECT_EQ(j["lost_runs"], 0);
  const robot::RobotLog s = robot::read_robot_log(log);
  std::vector<Pose> truth;
  for (const auto& t : s.truth) truth.emplace_back(t.position(0), t.position(1), *t.heading);
  expect_runs_within(j, rmse_bound(map, truth, s.laser_scans, j), r.out);
}

// Without truth the filter runs, but scores nothing: exit 1 unless --allow-empty (then the
// position metrics are null); a known start has no pose to start from.
TEST(SimulateLaserCli, RobotLogWithoutTruthScoresNothingUnlessAllowed) {
  TempDir dir("simulate_laser_no_truth");
  const fs::path yaml = write_room_map(dir);
  const fs::path full = dir.path() / "full.txt", bare = dir.path() / "bare.txt";
  ASSERT_EQ(run_cli(fmt::format("simulate --map '{}' --format robot-log --out '{}'", yaml.string(),
                                full.string()))
                .code,
            0);
  std::istringstream in(implicit::test::read_file(full));
  std::string text, line;
  while (std::getline(in, line))
    if (line.rfind("truth ", 0) != 0) text += line + "\n";
  implicit::test::write_file(bare, text);
  const std::string mcl =
      "mcl --sensor laser --data '" + bare.string() + "' -M 50 --runs 1 --json --quiet";
  const auto global = run_cli(mcl + " --init global");
  EXPECT_EQ(global.code, 1) << global.err;
  EXPECT_NE(global.err.find("scored nothing: scored_updates is 0"), std::string::npos)
      << global.err;
  const auto allowed = run_cli(mcl + " --init global --allow-empty");
  ASSERT_EQ(allowed.code, 0) << allowed.err;
  const auto j = nlohmann::json::parse(allowed.out);
  EXPECT_EQ(j["scored_updates"], 0);
  EXPECT_TRUE(j["position_rmse_m"]["mean"].is_null());
  EXPECT_TRUE(j["per_run"][0]["position_rmse_m"].is_null());
  const auto known = run_cli(mcl);
  EXPECT_EQ(known.code, 1);
  EXPECT_NE(known.err.find("no truth (with heading) at its time 0 s"), std::string::npos)
      << known.err;
  EXPECT_NE(known.err.find("--init global"), std::string::npos) << known.err;
}

// The example of docs/formats.md ("```robot-log-laser"), in the room it names: it parses, and
// `mcl --sensor laser` runs on it and scores every update.
TEST(SimulateLaserCli, DocumentedLaserLogRunsAndIsScored) {
  TempDir dir("documented_laser_log");
  write_room_map(dir);  // room.yaml, the example's `map`
  const std::string doc =
      implicit::test::read_file(fs::path(IMPLICIT_SOURCE_DIR) / "docs/formats.md");
  const std::string fence = "```robot-log-laser\n";
  const std::size_t begin = doc.find(fence);
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = doc.find("```", begin + fence.size());
  ASSERT_NE(end, std::string::npos);
  const fs::path log = dir.path() / "example.txt";
  implicit::test::write_file(log, doc.substr(begin + fence.size(), end - begin - fence.size()));
  const robot::RobotLog parsed = robot::read_robot_log(log);
  EXPECT_EQ(parsed.laser_scans.size(), 3u);
  EXPECT_EQ(parsed.odometry.size(), 3u);
  EXPECT_EQ(parsed.truth.size(), 3u);
  // Its readings are the room's, at the truth, to the 3 decimals written (inf: the wall is
  // beyond range_max).
  const OccupancyGrid map = robot::load_map(dir.path() / "room.yaml");
  for (std::size_t k = 0; k < parsed.laser_scans.size(); ++k) {
    const robot::LaserScan& scan = parsed.laser_scans[k];
    const robot::TruthRecord& truth = parsed.truth[k];
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double range =
          robot::cast_ray(map, truth.position, *truth.heading + scan.bearing(i), 30.0);
      if (std::isinf(scan.ranges[i])) {
        EXPECT_GE(range, scan.range_max) << k << " " << i;
      } else {
        EXPECT_NEAR(scan.ranges[i], range, 1e-3) << k << " " << i;
      }
    }
  }
  const auto r = run_cli("mcl --sensor laser --data '" + log.string() + "' -M 50 --runs 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["updates"], 3);
  EXPECT_EQ(j["scored_updates"], 3);
  EXPECT_EQ(j["odometry"], "recorded");
}

}  // namespace
