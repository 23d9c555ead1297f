// The CARMEN log reader: every message type on hand-written lines (values and beam angles checked
// exactly), gzip input, the no-return rule, every malformed case (a ParseError naming the file,
// the line and the field), and the bundled logs of data/carmen (counts from data/carmen/README.md,
// and the beam angles checked against the data themselves).
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/carmen.hpp"

namespace implicit::robot {
namespace {

constexpr double kDeg = kPi / 180.0;

// One line of each message type; the RLASER is skipped unless asked for.
const std::string kFixture =
    "# message formats defined: PARAM SYNC ODOM FLASER RLASER TRUEPOS\n"
    "PARAM robot_frontlaser_offset 0.0 nohost 0\n"
    "ODOM 1.5 -2 0.25 0.3 -0.1 0 10.5 host 10.6\n"
    "FLASER 4 1.5 2.25 81.91 0.75 1 2 0.5 1.1 2.1 0.6 11.25 host 11.3\n"
    "RLASER 3 1 2 3 0 0 3.5 0 0 3.5 11.5 host 11.5\n"
    "\n"
    "NEFF 7.5\n"
    "ROBOTLASER1 0 -1.5 3.0 0.75 30 0.01 0 5 1 2 3 30 4 2 0.5 0.5 1 2 0.1 1.1 2.1 0.2 0.5 0.05 "
    "0.3 0.2 0 12.5 host 12.6\n";

std::string error_of(const std::string& text, const CarmenOptions& options = {}) {
  try {
    parse_carmen(text, "bad.log", options);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Carmen, EveryMessageTypeIsReadExactly) {
  const CarmenLog log = parse_carmen(kFixture, "fixture.log");
  EXPECT_EQ(log.source, "fixture.log");
  EXPECT_EQ(log.lines, 8u);
  EXPECT_EQ(log.skipped_lines, 3u);  // PARAM, RLASER, NEFF
  ASSERT_EQ(log.scans.size(), 2u);
  ASSERT_EQ(log.laser_poses.size(), 2u);
  ASSERT_EQ(log.odometry_poses.size(), 2u);
  EXPECT_EQ(log.scan_lines, (std::vector<std::size_t>{4, 8}));
  EXPECT_EQ(log.rear, (std::vector<bool>{false, false}));

  ASSERT_EQ(log.odometry.size(), 1u);
  EXPECT_EQ(log.odometry[0].time, 10.5);
  EXPECT_EQ(log.odometry[0].pose, Pose(1.5, -2, 0.25));
  EXPECT_EQ(log.odometry[0].tv, 0.3);
  EXPECT_EQ(log.odometry[0].rv, -0.1);

  const LaserScan& f = log.scans[0];  // FLASER: 4 beams over 180 degrees, ends included
  EXPECT_EQ(f.ranges, (std::vector<double>{1.5, 2.25, 81.91, 0.75}));
  EXPECT_EQ(f.time, 11.25);
  EXPECT_EQ(f.angle_min, -kPi / 2);
  EXPECT_DOUBLE_EQ(f.angle_increment, kPi / 3);
  EXPECT_DOUBLE_EQ(f.bearing(3), kPi / 2);
  EXPECT_EQ(f.range_min, 0.0);
  EXPECT_EQ(f.range_max, 80.0);  // largest old-format reading 81.91 >= 80
  EXPECT_TRUE(f.is_hit(0));
  EXPECT_FALSE(f.is_hit(2));
  EXPECT_EQ(log.laser_poses[0], Pose(1, 2, 0.5));
  EXPECT_EQ(log.odometry_poses[0], Pose(1.1, 2.1, 0.6));

  const LaserScan& r = log.scans[1];  // ROBOTLASER1: its own angles and maximum range
  EXPECT_EQ(r.ranges, (std::vector<double>{1, 2, 3, 30, 4}));
  EXPECT_EQ(r.time, 12.5);
  EXPECT_EQ(r.angle_min, -1.5);
  EXPECT_EQ(r.angle_increment, 0.75);
  EXPECT_EQ(r.range_max, 30.0);
  EXPECT_FALSE(r.is_hit(3));
  EXPECT_TRUE(r.is_hit(4));
  EXPECT_EQ(log.laser_poses[1], Pose(1, 2, 0.1));
  EXPECT_EQ(log.odometry_poses[1], Pose(1.1, 2.1, 0.2));
}

TEST(Carmen, RearLaserOnlyWhenAsked) {
  const CarmenLog log = parse_carmen(kFixture, "fixture.log", {.rear_laser = true});
  ASSERT_EQ(log.scans.size(), 3u);
  EXPECT_EQ(log.skipped_lines, 2u);
  EXPECT_EQ(log.rear, (std::vector<bool>{false, true, false}));
  EXPECT_EQ(log.scans[1].ranges, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(log.laser_poses[1], Pose(0, 0, 3.5));
  EXPECT_EQ(log.scan_lines[1], 5u);
  EXPECT_EQ(parse_carmen(kFixture + "ROBOTLASER2 " + kFixture.substr(kFixture.rfind("0 -1.5")),
                         "f.log", {.rear_laser = true})
                .rear.back(),
            true);
}

// CARMEN's and GMapping's rule: from -90 degrees, 1 degree apart for 180/181 beams, 0.5 for
// 360/361; so 180 beams end at +89 and 181 at +90 degrees.
TEST(Carmen, BeamAnglesOfTheOldFormat) {
  EXPECT_DOUBLE_EQ(carmen_angle_increment(180), 1 * kDeg);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(181), 1 * kDeg);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(360), 0.5 * kDeg);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(361), 0.5 * kDeg);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(91), 2 * kDeg);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(2), kPi);
  EXPECT_DOUBLE_EQ(carmen_angle_increment(1), kPi);
  const struct {
    std::size_t n;
    double last_deg;
  } cases[] = {{180, 89}, {181, 90}, {360, 89.5}, {361, 90}, {91, 90}};
  for (const auto& c : cases) {
    std::string line = fmt::format("FLASER {}", c.n);
    for (std::size_t i = 0; i < c.n; ++i) line += " 2.5";
    line += " 0 0 0 0 0 0 1 h 1\n";
    const LaserScan scan = parse_carmen(line, "n.log").scans.at(0);
    ASSERT_EQ(scan.size(), c.n);
    EXPECT_EQ(scan.bearing(0), -kPi / 2);
    EXPECT_NEAR(scan.bearing(c.n - 1), c.last_deg * kDeg, 1e-12) << c.n << " beams";
  }
}

LaserScan one_scan(const std::string& ranges, const CarmenOptions& options = {}) {
  const std::size_t n = static_cast<std::size_t>(std::count(ranges.begin(), ranges.end(), ' ')) + 1;
  return parse_carmen(fmt::format("FLASER {} {} 0 0 0 0 0 0 1 h 1\n", n, ranges), "r.log", options)
      .scans.at(0);
}

TEST(Carmen, NoReturnRule) {
  // At or above 80 m in a log reaching 80 m: no return (Intel's 81.83, FR079's 81.91).
  LaserScan s = one_scan("79.5 81.83 80 3");
  EXPECT_EQ(s.range_max, 80.0);
  EXPECT_TRUE(s.is_hit(0));
  EXPECT_FALSE(s.is_hit(1));
  EXPECT_FALSE(s.is_hit(2));
  // Largest reading 50 m: the readings equal to it are no return (ACES).
  s = one_scan("49.91 50 12 50");
  EXPECT_EQ(s.range_max, 50.0);
  EXPECT_TRUE(s.is_hit(0));
  EXPECT_FALSE(s.is_hit(1));
  EXPECT_FALSE(s.is_hit(3));
  // No reading near a sensor maximum: nothing is taken for no return.
  s = one_scan("12 3 0");
  EXPECT_EQ(s.range_max, 80.0);
  EXPECT_TRUE(s.is_hit(0) && s.is_hit(1) && s.is_hit(2));
  // The option overrides the rule, and a ROBOTLASER1's own maximum_range too.
  s = one_scan("49.91 50 12 50", {.range_max = 20});
  EXPECT_EQ(s.range_max, 20.0);
  EXPECT_FALSE(s.is_hit(0));
  EXPECT_EQ(parse_carmen(kFixture, "f.log", {.range_max = 2.5}).scans[1].range_max, 2.5);
  EXPECT_THROW(parse_carmen(kFixture, "f.log", {.range_max = -1}), InvalidArgument);
  EXPECT_THROW(parse_carmen(kFixture, "f.log", {.range_max = std::nan("")}), InvalidArgument);
}

TEST(Carmen, GzipIsDetectedFromTheContent) {
  const auto dir =
      std::filesystem::temp_directory_path() / fmt::format("implicit-carmen-test-{}", ::getpid());
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "fixture.clf";  // gzip without a .gz name
  gzFile gz = gzopen(file.string().c_str(), "wb");
  ASSERT_NE(gz, nullptr);
  ASSERT_EQ(gzwrite(gz, kFixture.data(), static_cast<unsigned>(kFixture.size())),
            static_cast<int>(kFixture.size()));
  ASSERT_EQ(gzclose(gz), Z_OK);
  const CarmenLog from_gz = read_carmen(file);
  const CarmenLog from_text = parse_carmen(kFixture, file.string());
  EXPECT_EQ(from_gz.source, file.string());
  ASSERT_EQ(from_gz.scans.size(), from_text.scans.size());
  for (std::size_t k = 0; k < from_gz.scans.size(); ++k) {
    EXPECT_EQ(from_gz.scans[k].ranges, from_text.scans[k].ranges);
    EXPECT_EQ(from_gz.laser_poses[k], from_text.laser_poses[k]);
  }
  EXPECT_EQ(from_gz.lines, from_text.lines);
  // A missing file is named.
  try {
    read_carmen(dir / "missing.log");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.log"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Carmen, CommentsBlankLinesAndCarriageReturnsKeepLineNumbers) {
  const std::string text =
      "# comment\r\n\r\n   \nFLASER 2 1 1 0 0 0 0 0 0 1 h 1\r\nFLASER 2 1 1 nan 0 0 0 0 0 2 h "
      "2\r\n";
  EXPECT_EQ(error_of(text), "bad.log:5: FLASER field 'x': expected a finite number, got 'nan'");
  EXPECT_EQ(parse_carmen(text.substr(0, text.rfind("FLASER")), "ok.log").scans.size(), 1u);
}

TEST(Carmen, MalformedOldLaserLinesNameFileLineAndField) {
  const std::string ok = "FLASER 2 1 1 0 0 0 0 0 0 1 h 1\n";
  const std::string layout =
      "n = 3 ranges, x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname "
      "logger_timestamp (13 fields)";
  EXPECT_EQ(error_of(ok + "FLASER 3 1 2 0 0 0 0 0 0 1.5 h 1.5\n"),
            "bad.log:2: FLASER expected " + layout + ", got 12 fields (a truncated line?)");
  EXPECT_EQ(error_of(ok + "FLASER 3 1 2 3 4 0 0 0 0 0 0 1.5 h 1.5\n"),
            "bad.log:2: FLASER expected " + layout + ", got 14 fields");
  EXPECT_EQ(error_of("FLASER\n"),
            "bad.log:1: FLASER expected n, the number of readings, got nothing");
  EXPECT_EQ(
      error_of("FLASER 2 1 x 0 0 0 0 0 0 1 h 1\n"),
      "bad.log:1: FLASER field 'range of beam 1': expected a finite number >= 0 [m], got 'x'");
  EXPECT_EQ(
      error_of("FLASER 2 -1 1 0 0 0 0 0 0 1 h 1\n"),
      "bad.log:1: FLASER field 'range of beam 0': expected a finite number >= 0 [m], got '-1'");
  EXPECT_EQ(
      error_of("FLASER 2 inf 1 0 0 0 0 0 0 1 h 1\n"),
      "bad.log:1: FLASER field 'range of beam 0': expected a finite number >= 0 [m], got 'inf'");
  EXPECT_EQ(error_of("FLASER 0 0 0 0 0 0 0 1 h 1\n"),
            "bad.log:1: FLASER field 'n': expected an integer from 1 to 100000, got 0");
  EXPECT_EQ(error_of("FLASER -3 0 0 0 0 0 0 1 h 1\n"),
            "bad.log:1: FLASER field 'n': expected an integer from 1 to 100000, got -3");
  EXPECT_EQ(error_of("FLASER 100001 1 2\n"),
            "bad.log:1: FLASER field 'n': expected an integer from 1 to 100000, got 100001");
  EXPECT_EQ(error_of("FLASER 99999999999999999999 1\n"),
            "bad.log:1: FLASER field 'n': expected an integer, got '99999999999999999999'");
  EXPECT_EQ(error_of("FLASER 2.5 1 1 0 0 0 0 0 0 1 h 1\n"),
            "bad.log:1: FLASER field 'n': expected an integer, got '2.5'");
  EXPECT_EQ(error_of("FLASER 2 1 1 0 0 0 0 NaN 0 1 h 1\n"),
            "bad.log:1: FLASER field 'odom_y': expected a finite number, got 'NaN'");
  EXPECT_EQ(error_of("FLASER 2 1 1 nan nan nan 0 0 0 1 h 1\n"),  // the first bad field
            "bad.log:1: FLASER field 'x': expected a finite number, got 'nan'");
  EXPECT_EQ(error_of("FLASER 2 1 1 0 0 inf 0 0 0 1 h 1\n"),
            "bad.log:1: FLASER field 'theta': expected a finite number, got 'inf'");
  EXPECT_EQ(error_of("FLASER 2 1 1 0 0 0 0 0 0 12:30 h 1\n"),
            "bad.log:1: FLASER field 'ipc_timestamp': expected a finite number, got '12:30'");
  EXPECT_EQ(error_of("FLASER 2 1 1 0 0 0 0 0 0 1 h x\n"),
            "bad.log:1: FLASER field 'logger_timestamp': expected a finite number, got 'x'");
  EXPECT_EQ(error_of(ok + "RLASER 2 1 1 0 0 0 0 0 0 1 h x\n", {.rear_laser = true}),
            "bad.log:2: RLASER field 'logger_timestamp': expected a finite number, got 'x'");
  // Quoted text is made printable.
  EXPECT_EQ(error_of("FLASER 2 1 1 \x1b[2J 0 0 0 0 0 1 h 1\n"),
            "bad.log:1: FLASER field 'x': expected a finite number, got '\\x1b[2J'");
}

TEST(Carmen, MalformedRobotLaserLinesNameFileLineAndField) {
  const std::string head = "ROBOTLASER1 0 -1.5 3.0 0.75 30 0.01 0 ";
  const std::string tail = " 1 2 0.1 1.1 2.1 0.2 0.5 0.05 0.3 0.2 0 12.5 host 12.6\n";
  EXPECT_EQ(error_of(head + "2 1 2 0" + tail), "no error");
  EXPECT_EQ(error_of("ROBOTLASER1 0 -1.5 3.0 0.75\n"),
            "bad.log:1: ROBOTLASER1 expected laser_type start_angle field_of_view "
            "angular_resolution maximum_range accuracy remission_mode num_readings first, got 4 "
            "fields (a truncated line?)");
  EXPECT_EQ(error_of(head + "5 1 2\n"),
            "bad.log:1: ROBOTLASER1 expected num_readings = 5 ranges, then num_remissions, got 10 "
            "fields in all (a truncated line?)");
  // m = 3 remissions promised, 2 given: the line is one field short.
  EXPECT_EQ(error_of(head + "2 1 2 3 0.5 0.5" + tail),
            "bad.log:1: ROBOTLASER1 expected laser_type start_angle field_of_view "
            "angular_resolution maximum_range accuracy remission_mode num_readings, 2 ranges, "
            "num_remissions, 3 remissions, laser_x laser_y laser_theta robot_x robot_y robot_theta "
            "tv rv forward_safety_dist side_safety_dist turn_axis ipc_timestamp ipc_hostname "
            "logger_timestamp (28 fields), got 27 fields (a truncated line?)");
  EXPECT_EQ(error_of(head + "2 1 2 200000" + tail),
            "bad.log:1: ROBOTLASER1 field 'num_remissions': expected an integer from 0 to 100000, "
            "got 200000");
  EXPECT_EQ(error_of(head + "2 1 2 1 nan" + tail),
            "bad.log:1: ROBOTLASER1 field 'remission 0': expected a finite number, got 'nan'");
  EXPECT_EQ(error_of(head + "0 0" + tail),
            "bad.log:1: ROBOTLASER1 field 'num_readings': expected an integer from 1 to 100000, "
            "got 0");
  EXPECT_EQ(error_of("ROBOTLASER1 0 -1.5 3.0 0 30 0.01 0 2 1 2 0" + tail),
            "bad.log:1: ROBOTLASER1 field 'angular_resolution': expected != 0, got 0");
  EXPECT_EQ(error_of("ROBOTLASER1 0 -1.5 3.0 0.75 -30 0.01 0 2 1 2 0" + tail),
            "bad.log:1: ROBOTLASER1 field 'maximum_range': expected > 0 [m], got -30");
  EXPECT_EQ(error_of("ROBOTLASER1 0 nan 3.0 0.75 30 0.01 0 2 1 2 0" + tail),
            "bad.log:1: ROBOTLASER1 field 'start_angle': expected a finite number, got 'nan'");
  EXPECT_EQ(error_of(head + "2 1 2 0 1 2 0.1 1.1 2.1 0.2 0.5 0.05 0.3 0.2 0 soon host 12.6\n"),
            "bad.log:1: ROBOTLASER1 field 'ipc_timestamp': expected a finite number, got 'soon'");
  EXPECT_EQ(error_of(head + "2 1 2 0 1 2 0.1 1.1 inf 0.2 0.5 0.05 0.3 0.2 0 1 host 1\n"),
            "bad.log:1: ROBOTLASER1 field 'robot_y': expected a finite number, got 'inf'");
}

TEST(Carmen, MalformedOdometryAndOtherLines) {
  const std::string ok = "FLASER 2 1 1 0 0 0 0 0 0 1 h 1\n";
  EXPECT_EQ(error_of(ok + "ODOM 1 2 3 0 0 0 1 h\n"),
            "bad.log:2: ODOM expected x y theta tv rv accel ipc_timestamp ipc_hostname "
            "logger_timestamp (9 fields), got 8 fields (a truncated line?)");
  EXPECT_EQ(error_of(ok + "ODOM 1 2 3 nan 0 0 1 h 1\n"),
            "bad.log:2: ODOM field 'tv': expected a finite number, got 'nan'");
  EXPECT_EQ(error_of(ok + "ODOM 1 2 3 0 0 0 t h 1\n"),
            "bad.log:2: ODOM field 'ipc_timestamp': expected a finite number, got 't'");
  EXPECT_EQ(error_of(ok + "time,x,y\n"),
            "bad.log:2: expected a CARMEN message name (upper-case letters, digits, '_') first, "
            "got 'time,x,y'");
  EXPECT_EQ(error_of(ok + "SYNC anything at all\nTRUEPOS 1 2\n"), "no error");
}

TEST(Carmen, ALogWithoutLaserScansIsAnError) {
  EXPECT_EQ(error_of(""),
            "bad.log: expected at least one laser scan (a FLASER or ROBOTLASER1 message), got none "
            "in 0 lines (0 lines of other messages skipped)");
  EXPECT_EQ(error_of("# only\nODOM 1 2 3 0 0 0 1 h 1\nRLASER 2 1 1 0 0 0 0 0 0 1 h 1\n"),
            "bad.log: expected at least one laser scan (a FLASER or ROBOTLASER1 message), got none "
            "in 3 lines (1 lines of other messages skipped)");
}

// The bundled logs (data/carmen/README.md).
struct Bundled {
  const char* file;
  std::size_t scans, beams, odometry, lines;
  double range_max;
  std::size_t no_returns;  // readings at the log's maximum (81.83, 50, 81.91 m), counted by awk
};
constexpr Bundled kBundled[] = {
    {"intel-corrected.log.gz", 910, 180, 14541, 16365, 80.0, 4172},
    {"aces-corrected.log.gz", 440, 180, 7814, 8700, 50.0, 620},
    {"freiburg-079-corrected.log.gz", 4791, 360, 9725, 19496, 80.0, 36004}};

const CarmenLog& bundled(std::size_t k) {
  static std::vector<CarmenLog> logs;
  if (logs.empty())
    for (const Bundled& b : kBundled)
      logs.push_back(
          read_carmen(std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data" / "carmen" / b.file));
  return logs[k];
}

TEST(Carmen, BundledLogsHaveTheirScansAndBeams) {
  for (std::size_t k = 0; k < std::size(kBundled); ++k) {
    const Bundled& b = kBundled[k];
    const CarmenLog& log = bundled(k);
    SCOPED_TRACE(b.file);
    EXPECT_EQ(log.scans.size(), b.scans);
    EXPECT_EQ(log.odometry.size(), b.odometry);
    EXPECT_EQ(log.lines, b.lines);
    // Two comment lines; every other line is a scan, an ODOM or a skipped message (NEFF, PARAM).
    EXPECT_EQ(log.skipped_lines, b.lines - 2 - b.scans - b.odometry);
    std::size_t no_returns = 0;
    for (std::size_t s = 0; s < log.scans.size(); ++s) {
      for (std::size_t i = 0; i < log.scans[s].size(); ++i) no_returns += !log.scans[s].is_hit(i);
      ASSERT_EQ(log.scans[s].size(), b.beams) << "scan " << s;
      ASSERT_EQ(log.scans[s].range_max, b.range_max);
      // The corrected logs record one pose twice (data/carmen/README.md).
      ASSERT_EQ(log.laser_poses[s], log.odometry_poses[s]);
    }
    EXPECT_EQ(no_returns, b.no_returns);
    EXPECT_DOUBLE_EQ(log.scans[0].angle_increment, kPi / static_cast<double>(b.beams));
  }
}

// The poses were corrected by a grid SLAM program under some beam-angle convention: the map the
// scans draw is sharpest (fewest 5 cm cells hit) under that convention. Rotating every beam by
// half a beam spacing either way (the centred convention, or its mirror) must blur it.
std::size_t cells_hit(const CarmenLog& log, double offset) {
  std::unordered_set<long long> cells;
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    const LaserScan& s = log.scans[k];
    const Pose& p = log.laser_poses[k];
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (!s.is_hit(i) || s.ranges[i] > 20) continue;  // far hits blur for other reasons
      const double b = p(2) + s.bearing(i) + offset;
      const long long cx = std::llround((p(0) + s.ranges[i] * std::cos(b)) / 0.05);
      const long long cy = std::llround((p(1) + s.ranges[i] * std::sin(b)) / 0.05);
      cells.insert(cx * 4000037LL + cy);
    }
  }
  return cells.size();
}

TEST(Carmen, BundledMapsAreSharpestWithTheChosenBeamAngles) {
  for (std::size_t k = 0; k < std::size(kBundled); ++k) {
    const CarmenLog& log = bundled(k);
    const double half = 0.5 * log.scans[0].angle_increment;
    const std::size_t chosen = cells_hit(log, 0.0);
    EXPECT_LT(chosen, cells_hit(log, half)) << kBundled[k].file;
    EXPECT_LT(chosen, cells_hit(log, -half)) << kBundled[k].file;
  }
}

}  // namespace
}  // namespace implicit::robot
