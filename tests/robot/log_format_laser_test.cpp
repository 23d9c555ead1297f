// The robot log's records of laser runs (map, laser_mount, odometry, laser): exact round trip,
// the bad-input table (every message names the file, the line and the field), the map file
// relative to the log, the format detection, and odometry interpolated at scan times.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::robot {
namespace {

// Every new record, with the awkward values: inf (no return), a reading at range_max, a scan
// from left to right (negative increment, as LaserScan allows), numbers that need 17 digits.
const char* kLaserLog = R"(# implicit robot log v1
map maps/lab.yaml
laser_mount 0.2 -0.05 0.01
odometry 0 0 0 0
laser 0.1 -1.5707963267948966 0.78539816339744828 0.05 30 5 2.1 inf 1.87 30 0.5
odometry 0.5 0.25 0.1 3.1
laser 0.6 1.5707963267948966 -0.78539816339744828 0 8 3 7.99 1 inf
odometry 1 0.5 0.2 -3.1
truth 0 1 2 0
truth 1 1.5 2
)";

RobotLog parse_laser_log(const std::string& text) {
  std::istringstream in(text);
  return parse_robot_log(in, "laser.log");
}

std::string write(const RobotLog& log) {
  std::ostringstream out;
  write_robot_log(out, log);
  return out.str();
}

TEST(RobotLogLaser, ParsesEveryRecord) {
  const RobotLog log = parse_laser_log(kLaserLog);
  ASSERT_TRUE(log.map.has_value());
  EXPECT_EQ(log.map->file, "maps/lab.yaml");
  EXPECT_EQ(log.map->line, 2u);
  ASSERT_TRUE(log.laser_mount.has_value());
  EXPECT_EQ(log.laser_mount->x, 0.2);
  EXPECT_EQ(log.laser_mount->y, -0.05);
  EXPECT_EQ(log.laser_mount->yaw, 0.01);
  ASSERT_EQ(log.odometry.size(), 3u);
  EXPECT_EQ(log.odometry[1].time, 0.5);
  EXPECT_EQ(log.odometry[1].pose, Pose(0.25, 0.1, 3.1));
  ASSERT_EQ(log.laser_scans.size(), 2u);
  const LaserScan& a = log.laser_scans[0];
  EXPECT_EQ(a.time, 0.1);
  EXPECT_EQ(a.angle_min, -1.5707963267948966);
  EXPECT_EQ(a.angle_increment, 0.78539816339744828);
  EXPECT_EQ(a.range_min, 0.05);
  EXPECT_EQ(a.range_max, 30.0);
  ASSERT_EQ(a.size(), 5u);
  EXPECT_TRUE(std::isinf(a.ranges[1]));
  EXPECT_FALSE(a.is_hit(1));  // inf: no return
  EXPECT_FALSE(a.is_hit(3));  // at range_max: no return
  EXPECT_TRUE(a.is_hit(4));
  EXPECT_LT(log.laser_scans[1].angle_increment, 0.0);
  for (const LaserScan& s : log.laser_scans) EXPECT_NO_THROW(s.validate("laser.log"));
  ASSERT_EQ(log.truth.size(), 2u);
  EXPECT_TRUE(log.landmarks.size() == 0 && log.controls.empty() && log.scans.empty());
}

// Written with 17 significant digits, read back bit for bit, and written again identically.
TEST(RobotLogLaser, RoundTripsEveryRecordExactly) {
  RobotLog log = parse_laser_log(kLaserLog);
  // Values that a shorter format would round: 0.1 + 0.2, pi / 3, a subnormal-free tiny number.
  log.odometry.push_back({1.5, Pose(0.1 + 0.2, kPi / 3, -1e-300)});
  log.laser_scans.push_back(log.laser_scans[0]);
  log.laser_scans.back().time = 1.25;
  log.laser_scans.back().ranges[0] = 1.0 / 3.0;
  const std::string text = write(log);
  const RobotLog again = parse_laser_log(text);
  ASSERT_TRUE(again.map && again.laser_mount);
  EXPECT_EQ(again.map->file, log.map->file);
  EXPECT_EQ(again.laser_mount->x, log.laser_mount->x);
  EXPECT_EQ(again.laser_mount->y, log.laser_mount->y);
  EXPECT_EQ(again.laser_mount->yaw, log.laser_mount->yaw);
  ASSERT_EQ(again.odometry.size(), log.odometry.size());
  for (std::size_t k = 0; k < log.odometry.size(); ++k) {
    EXPECT_EQ(again.odometry[k].time, log.odometry[k].time) << k;
    EXPECT_EQ(again.odometry[k].pose, log.odometry[k].pose) << k;
  }
  ASSERT_EQ(again.laser_scans.size(), log.laser_scans.size());
  for (std::size_t k = 0; k < log.laser_scans.size(); ++k) {
    const LaserScan &a = log.laser_scans[k], &b = again.laser_scans[k];
    EXPECT_EQ(b.time, a.time) << k;
    EXPECT_EQ(b.angle_min, a.angle_min) << k;
    EXPECT_EQ(b.angle_increment, a.angle_increment) << k;
    EXPECT_EQ(b.range_min, a.range_min) << k;
    EXPECT_EQ(b.range_max, a.range_max) << k;
    EXPECT_EQ(b.ranges, a.ranges) << k;  // inf == inf
  }
  EXPECT_EQ(write(again), text);
  // Optional records stay absent.
  const RobotLog bare = parse_laser_log("odometry 0 0 0 0\n");
  EXPECT_FALSE(parse_laser_log(write(bare)).map.has_value());
  EXPECT_FALSE(parse_laser_log(write(bare)).laser_mount.has_value());
}

TEST(RobotLogLaser, AMapFileThatCannotBeOneWordIsNotWritten) {
  RobotLog log;
  log.map = MapReference{"my map.yaml", 0};
  std::ostringstream out;
  EXPECT_THROW(write_robot_log(out, log), InvalidArgument);
  log.map->file = "lab#2.yaml";
  EXPECT_THROW(write_robot_log(out, log), InvalidArgument);
}

struct LaserBadCase {
  const char* text;
  const char* expected;  // substring of the message
};

TEST(RobotLogLaser, RejectsMalformedRecordsNamingLineAndField) {
  const std::string scan = "laser 1 -1.5 0.5 0 10 3 ";
  const std::string rows[][2] = {
      {scan + "1 nan 2\n",
       "laser.log:1: field 'r_2': expected a range >= 0 or inf (no return), "
       "got 'nan'"},
      {scan + "1 -2 2\n", "laser.log:1: field 'r_2': expected a range >= 0 or inf"},
      {scan + "1 2\n", "laser.log:1: field 'n': expected 3 readings after it, got 2"},
      {scan + "1 2 3 4\n", "laser.log:1: field 'n': expected 3 readings after it, got 4"},
      {"laser 1 -1.5 0.5 0 10 0\n", "laser.log:1: record 'laser': expected 'laser t angle_min"},
      {"laser 1 -1.5 0.5 0 10 -2 1\n", "laser.log:1: field 'n': expected a non-negative integer"},
      {"laser 1 -1.5 0 0 10 1 1\n", "laser.log:1: field 'angle_increment': expected a non-zero"},
      {"laser 1 -1.5 nan 0 10 1 1\n", "laser.log:1: field 'angle_increment': expected a finite"},
      {"laser 1 inf 0.5 0 10 1 1\n", "laser.log:1: field 'angle_min': expected a finite number"},
      {"laser 1 -1.5 0.5 -0.1 10 1 1\n", "laser.log:1: field 'range_min': expected >= 0, got -0.1"},
      {"laser 1 -1.5 0.5 2 2 1 1\n",
       "laser.log:1: field 'range_max': expected more than "
       "range_min = 2, got 2"},
      {"laser 1 -1.5 0.5 0 inf 1 1\n", "laser.log:1: field 'range_max': expected a finite"},
      {scan + "1 2 3\n" + scan + "1 2 3\n",
       "laser.log:2: field 'time': expected a time after 1 "
       "(previous 'laser' record), got 1"},
      {"odometry 2 0 0 0\nodometry 1 0 0 0\n",
       "laser.log:2: field 'time': expected a time after "
       "2 (previous 'odometry' record), got 1"},
      {"odometry 1 0 0\n", "laser.log:1: record 'odometry': expected 'odometry t x y theta'"},
      {"odometry 1 0 0 nan\n", "laser.log:1: field 'theta': expected a finite number"},
      {"map a.yaml\nmap b.yaml\n",
       "laser.log:2: expected one 'map' record, got a second one (the first: line 1)"},
      {"map my map.yaml\n", "laser.log:1: record 'map': expected 'map FILE'"},
      {"map\n", "laser.log:1: record 'map': expected 'map FILE'"},
      {"laser_mount 0 0 0\nlaser_mount 0 0 0\n", "laser.log:2: expected one 'laser_mount'"},
      {"laser_mount 0 0\n", "laser.log:1: record 'laser_mount': expected 'laser_mount x y theta'"},
      {"laser_mount 0 x 0\n", "laser.log:1: field 'y': expected a finite number, got 'x'"},
  };
  for (const auto& [text, expected] : rows) {
    try {
      parse_laser_log(text);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
          << "message: " << e.what() << "\nexpected to contain: " << expected;
    }
  }
}

std::filesystem::path scratch(const std::string& tag) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("implicit_" + tag + "_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "maps");
  return dir;
}

// The map file is looked up beside the log, not in the working folder; a missing one is an
// error naming the log's line.
TEST(RobotLogLaser, MapFileIsRelativeToTheLogsFolderAndMustExist) {
  const auto dir = scratch("log_map");
  std::ofstream(dir / "run.log") << "# a laser run\nmap maps/lab.yaml\nodometry 0 0 0 0\n";
  std::string message;
  try {
    read_robot_log(dir / "run.log");
  } catch (const ParseError& e) {
    message = e.what();
  }
  EXPECT_EQ(message, (dir / "run.log").string() +
                         ":2: field 'file': expected an existing map file (relative to the log's "
                         "folder), got 'maps/lab.yaml' (no file " +
                         (dir / "maps/lab.yaml").string() + ")");
  std::ofstream(dir / "maps/lab.yaml") << "image: lab.pgm\n";
  const RobotLog log = read_robot_log(dir / "run.log");
  EXPECT_EQ(map_file(log), dir / "maps/lab.yaml");
  // An absolute name is kept as it is; a log without the record has no map file.
  EXPECT_EQ(map_file(parse_laser_log("map /data/lab.yaml\n")),
            std::filesystem::path("/data/lab.yaml"));
  EXPECT_EQ(map_file(parse_laser_log("odometry 0 0 0 0\n")), std::filesystem::path());
  std::filesystem::remove_all(dir);
}

TEST(RobotLogLaser, FormatIsToldFromTheFirstRecord) {
  EXPECT_TRUE(is_robot_log(kLaserLog));
  EXPECT_TRUE(is_robot_log("\n  # comment\n\ttruth 0 1 2\n"));
  EXPECT_TRUE(is_robot_log("landmark 1 2 3"));  // no final line break
  // CARMEN messages, an empty file, comments only, a word that is no record kind.
  EXPECT_FALSE(
      is_robot_log("# CARMEN log\nPARAM robot_width 0.5\nFLASER 2 1 1 0 0 0 0 0 0 1 h 1\n"));
  EXPECT_FALSE(is_robot_log("ODOM 0 0 0 0 0 0 1 h 1\n"));
  EXPECT_FALSE(is_robot_log(""));
  EXPECT_FALSE(is_robot_log("# only a comment\n\n"));
  EXPECT_FALSE(is_robot_log("lasers 1 2 3\n"));
}

// Odometry at scan times: linear between records, heading along the shorter arc (across +-pi
// too), exact at a record, NaN outside the records' time span.
TEST(RobotLogLaser, OdometryIsInterpolatedAtScanTimes) {
  const RobotLog log =
      parse_laser_log("odometry 0 0 0 0\nodometry 1 1 2 3.0\nodometry 2 1 2 -3.0\n");
  const std::vector<Pose> p = interpolate_odometry(log, {-0.5, 0.0, 0.25, 1.0, 1.5, 2.0, 2.5});
  ASSERT_EQ(p.size(), 7u);
  EXPECT_TRUE(std::isnan(p[0](0)));
  EXPECT_EQ(p[1], Pose(0, 0, 0));
  EXPECT_NEAR(p[2](0), 0.25, 1e-15);
  EXPECT_NEAR(p[2](1), 0.5, 1e-15);
  EXPECT_NEAR(p[2](2), 0.75, 1e-15);
  EXPECT_EQ(p[3], Pose(1, 2, 3.0));
  // From 3.0 to -3.0 the short way is through pi: 3.0 + (2 pi - 6) / 2 at the midpoint.
  EXPECT_NEAR(p[4](2), 3.0 + (2 * kPi - 6.0) / 2, 1e-12);
  EXPECT_EQ(p[5], Pose(1, 2, -3.0));
  EXPECT_TRUE(std::isnan(p[6](2)));
  EXPECT_TRUE(std::isnan(interpolate_odometry(parse_laser_log(""), {0.0})[0](0)));
  // Truth at arbitrary times agrees with its schedule form (same records, same rule).
  const RobotLog truth = parse_laser_log("truth 0 0 0 0\ntruth 0.5 1 0 1\ntruth 5 2 0\n");
  const TruthTrack t = interpolate_truth(truth, std::vector<double>{0.25, 1.0});
  EXPECT_NEAR(t.position[0](0), 0.5, 1e-15);
  EXPECT_NEAR(t.heading[0], 0.5, 1e-15);
  EXPECT_TRUE(std::isnan(t.position[1](0)));  // inside a 4.5 s gap
}

}  // namespace
}  // namespace implicit::robot
