// The ROS bag readers against fixtures written by independent tools (tests/data/bags/generate.mjs:
// @mcap/core, sql.js, @foxglove/rosmsg2-serialization and -serialization; the ROS 1 container
// written by the generator and read back by @foxglove/rosbag) from the first 31 laser messages of
// the Intel log: every value read is compared with the value written, recomputed here from the log.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <type_traits>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

const std::filesystem::path kBagDir =
    std::filesystem::path(IMPLICIT_SOURCE_DIR) / "tests/data/bags";

// The generator's choices (generate.mjs): scan k is the log's laser message k stamped 1 ms after
// it, odometry message j the pose of its message j at its time; the static transforms
// base_footprint -> base_link -> laser.
constexpr std::size_t kBagScans = 30, kBagOdometry = 31;
constexpr double kBagScanDelay = 0.001;  // [s]

/// The first 31 laser messages of the Intel log (the generator's source).
const CarmenLog& bag_source_log() {
  static const CarmenLog log = [] {
    const std::string text = read_text_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) /
                                            "data/carmen/intel-corrected.log.gz");
    std::size_t pos = 0, lasers = 0;
    while (lasers < 31 && (pos = text.find("\nFLASER ", pos)) != std::string::npos) {
      ++lasers;
      ++pos;
    }
    return parse_carmen(text.substr(0, text.find('\n', pos) + 1), "intel");
  }();
  return log;
}

/// A time as the generator stamps it (whole seconds and rounded nanoseconds), read back.
double bag_stamp(double t) {
  const double sec = std::floor(t);
  return sec + 1e-9 * std::floor((t - sec) * 1e9 + 0.5);
}

std::string bag_bytes(const std::string& file) {
  std::ifstream in(kBagDir / file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string bag_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const ParseError& e) {
    return e.what();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

const std::vector<std::string> kBagFiles = {"intel-zstd.mcap",
                                            "intel-lz4.mcap",
                                            "intel-plain.mcap",
                                            "intel-rosbag2",
                                            "intel-rosbag2/intel-rosbag2_0.db3",
                                            "intel.bag",
                                            "intel-lz4.bag",
                                            "intel-bz2.bag"};

TEST(Bag, EveryFormatGivesTheValuesWritten) {
  const CarmenLog& intel = bag_source_log();
  for (const std::string& file : kBagFiles) {
    SCOPED_TRACE(file);
    const BagLaserLog b = read_bag_laser_log(kBagDir / file);
    EXPECT_TRUE(b.mount_from_tf);
    EXPECT_EQ(b.base_frame, "base_footprint");  // the odometry's child frame
    EXPECT_EQ(b.laser_frame, "laser");
    EXPECT_NEAR(b.mount.x, 0.1, 1e-15);
    EXPECT_NEAR(b.mount.y, 0.02, 1e-15);
    EXPECT_NEAR(b.mount.yaw, 0.05, 1e-15);
    EXPECT_EQ(b.scans_outside_odometry, 0u);
    const CarmenLog& log = b.log;
    ASSERT_EQ(log.odometry.size(), kBagOdometry);
    for (std::size_t j = 0; j < kBagOdometry; ++j) {
      const std::size_t i = j;
      EXPECT_EQ(log.odometry[j].time, bag_stamp(intel.scans[i].time));
      EXPECT_EQ(log.odometry[j].pose(0), intel.laser_poses[i](0));
      EXPECT_EQ(log.odometry[j].pose(1), intel.laser_poses[i](1));
      // Through a quaternion: the same angle, within (-pi, pi].
      EXPECT_NEAR(wrap_angle(log.odometry[j].pose(2) - intel.laser_poses[i](2)), 0.0, 1e-14);
      EXPECT_EQ(log.odometry[j].tv, 0.01 * static_cast<double>(j));
      EXPECT_EQ(log.odometry[j].rv, -0.02 * static_cast<double>(j));
    }
    ASSERT_EQ(log.scans.size(), kBagScans);
    for (std::size_t k = 0; k < kBagScans; ++k) {
      const std::size_t i = k;
      const LaserScan& s = log.scans[k];
      EXPECT_EQ(log.scan_lines[k], k);
      EXPECT_EQ(s.time, bag_stamp(intel.scans[i].time + kBagScanDelay));
      EXPECT_EQ(s.angle_min, static_cast<double>(static_cast<float>(-kPi / 2)));
      EXPECT_EQ(s.angle_increment, static_cast<double>(static_cast<float>(kPi / 180)));
      EXPECT_EQ(s.range_min, 0.0);
      EXPECT_EQ(s.range_max, 80.0);
      ASSERT_EQ(s.size(), 180u);
      for (std::size_t r = 0; r < 180; ++r) {
        const double written = static_cast<float>(intel.scans[i].ranges[r]);
        // The NaN and +inf of scan 1 (REP 117), and the SICK's 81.83 m, are no return.
        const bool none = (k == 1 && r < 2) || written > 80.0;
        EXPECT_EQ(s.ranges[r], none ? 80.0 : written) << "scan " << k << " beam " << r;
      }
      // The odometry pose at the scan's stamp: linear between the two recorded around it.
      const Pose& pa = intel.laser_poses[i];
      const Pose& pb = intel.laser_poses[i + 1];
      const double ta = bag_stamp(intel.scans[i].time), tb = bag_stamp(intel.scans[i + 1].time);
      const double w = (s.time - ta) / (tb - ta);
      ASSERT_GT(w, 0.0);
      Pose expected = pa + w * (pb - pa);
      expected(2) = pa(2) + w * wrap_angle(pb(2) - pa(2));
      EXPECT_NEAR((log.odometry_poses[k] - expected).norm(), 0.0, 1e-12) << "scan " << k;
      const Pose laser = compose(log.odometry_poses[k], Pose(0.1, 0.02, 0.05));
      EXPECT_NEAR((log.laser_poses[k] - laser).norm(), 0.0, 1e-12) << "scan " << k;
    }
  }
}

TEST(Bag, EveryFormatReadsTheSameLogBitForBit) {
  const BagLaserLog first = read_bag_laser_log(kBagDir / kBagFiles.front());
  for (const std::string& file : kBagFiles) {
    SCOPED_TRACE(file);
    const BagLaserLog b = read_bag_laser_log(kBagDir / file);
    ASSERT_EQ(b.log.scans.size(), first.log.scans.size());
    for (std::size_t k = 0; k < b.log.scans.size(); ++k) {
      EXPECT_EQ(b.log.scans[k].ranges, first.log.scans[k].ranges);
      EXPECT_EQ(b.log.laser_poses[k], first.log.laser_poses[k]);
      EXPECT_EQ(b.log.odometry_poses[k], first.log.odometry_poses[k]);
    }
  }
}

TEST(Bag, TopicsTypesCountsAndTransformsAsWritten) {
  const BagContents bag = read_bag(kBagDir / "intel-lz4.mcap");
  EXPECT_EQ(bag.format, "MCAP");
  const std::vector<std::pair<std::string, std::size_t>> counts = {
      {"/scan", 30}, {"/odom", 31}, {"/tf", 31}, {"/tf_static", 1}, {"/ground_truth", 30}};
  for (const auto& [name, n] : counts) {
    const std::size_t t = bag.find_topic(name);
    ASSERT_LT(t, bag.topics.size()) << name;
    EXPECT_EQ(
        static_cast<std::size_t>(std::count_if(bag.messages.begin(), bag.messages.end(),
                                               [&](const BagMessage& m) { return m.topic == t; })),
        n)
        << name;
  }
  EXPECT_EQ(bag.topics[bag.find_topic("/scan")].type, "sensor_msgs/msg/LaserScan");
  EXPECT_EQ(bag_base_type("sensor_msgs/msg/LaserScan"), "sensor_msgs/LaserScan");
  for (std::size_t i = 1; i < bag.messages.size(); ++i)
    EXPECT_LE(bag.messages[i - 1].time_ns, bag.messages[i].time_ns);
  const std::size_t s = bag.find_topic("/tf_static");
  const auto m = std::find_if(bag.messages.begin(), bag.messages.end(),
                              [&](const BagMessage& x) { return x.topic == s; });
  const std::vector<BagTransform> tf = decode_tf_message(m->data, BagEncoding::kCdr, "tf_static");
  ASSERT_EQ(tf.size(), 2u);
  EXPECT_EQ(tf[0].header.frame_id, "base_footprint");
  EXPECT_EQ(tf[0].child_frame_id, "base_link");
  EXPECT_EQ(tf[0].translation[2], 0.05);
  EXPECT_EQ(tf[1].header.frame_id, "base_link");
  EXPECT_EQ(tf[1].child_frame_id, "laser");
  EXPECT_EQ(tf[1].translation[0], 0.1);
  EXPECT_EQ(tf[1].translation[1], 0.02);
  EXPECT_EQ(tf[1].translation[2], 0.3);
  EXPECT_EQ(tf[1].rotation[2], std::sin(0.025));
  EXPECT_EQ(tf[1].rotation[3], std::cos(0.025));
  EXPECT_EQ(tf[1].header.time, bag_stamp(bag_source_log().scans[0].time));
}

TEST(Bag, PoseStampedOdometryAndChosenFrames) {
  const CarmenLog& intel = bag_source_log();
  BagOptions o;
  o.odom_topic = "/ground_truth";  // geometry_msgs/PoseStamped, at every scan's stamp
  const BagLaserLog b = read_bag_laser_log(kBagDir / "intel-zstd.mcap", o);
  EXPECT_EQ(b.base_frame, "base_link");  // a PoseStamped names no child frame
  EXPECT_NEAR(b.mount.x, 0.1, 1e-15);
  ASSERT_EQ(b.log.scans.size(), kBagScans);
  for (std::size_t k = 0; k < kBagScans; ++k) {
    EXPECT_EQ(b.log.odometry_poses[k](0), intel.laser_poses[k](0));
    EXPECT_NEAR(wrap_angle(b.log.odometry_poses[k](2) - intel.laser_poses[k](2)), 0.0, 1e-14);
  }
  // The laser as the robot's frame: no transform between a frame and itself.
  o.base_frame = "laser";
  const BagLaserLog same = read_bag_laser_log(kBagDir / "intel-zstd.mcap", o);
  EXPECT_TRUE(same.mount_from_tf);
  EXPECT_EQ(same.mount.x, 0.0);
  // A frame the transforms do not join: no mount (zero), and the log says so.
  o.base_frame = "map";
  const BagLaserLog none = read_bag_laser_log(kBagDir / "intel-zstd.mcap", o);
  EXPECT_FALSE(none.mount_from_tf);
  EXPECT_EQ(none.mount.x, 0.0);
}

TEST(Bag, CarmenTextReadsBackAsTheSameLog) {
  const BagLaserLog b = read_bag_laser_log(kBagDir / "intel-zstd.mcap");
  const CarmenLog back = parse_carmen(carmen_log_text(b.log), "converted.log");
  ASSERT_EQ(back.scans.size(), b.log.scans.size());
  for (std::size_t k = 0; k < back.scans.size(); ++k) {
    EXPECT_EQ(back.scans[k].time, b.log.scans[k].time);
    EXPECT_EQ(back.scans[k].angle_min, b.log.scans[k].angle_min);
    EXPECT_EQ(back.scans[k].angle_increment, b.log.scans[k].angle_increment);
    EXPECT_EQ(back.scans[k].range_min, b.log.scans[k].range_min);
    EXPECT_EQ(back.scans[k].range_max, b.log.scans[k].range_max);
    EXPECT_EQ(back.scans[k].ranges, b.log.scans[k].ranges);
    EXPECT_EQ(back.laser_poses[k], b.log.laser_poses[k]);
    EXPECT_EQ(back.odometry_poses[k], b.log.odometry_poses[k]);
  }
  ASSERT_EQ(back.odometry.size(), b.log.odometry.size());
  for (std::size_t j = 0; j < back.odometry.size(); ++j) {
    EXPECT_EQ(back.odometry[j].time, b.log.odometry[j].time);
    EXPECT_EQ(back.odometry[j].pose, b.log.odometry[j].pose);
    EXPECT_EQ(back.odometry[j].tv, b.log.odometry[j].tv);
    EXPECT_EQ(back.odometry[j].rv, b.log.odometry[j].rv);
  }
}

TEST(Bag, ChosenTopicsMustExistAndHaveTheirTypes) {
  const auto file = kBagDir / "intel-rosbag2";
  BagOptions o;
  o.scan_topic = "/nope";
  std::string e = bag_error([&] { read_bag_laser_log(file, o); });
  EXPECT_NE(e.find("intel-rosbag2: expected topic '/nope' (--scan-topic), got no such topic"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("/scan (sensor_msgs/msg/LaserScan)"), std::string::npos) << e;
  o.scan_topic = "/tf";
  e = bag_error([&] { read_bag_laser_log(file, o); });
  EXPECT_NE(e.find("topic '/tf' (--scan-topic): expected messages of type sensor_msgs/LaserScan, "
                   "got 'tf2_msgs/msg/TFMessage'"),
            std::string::npos)
      << e;
  o = {};
  o.odom_topic = "/scan";
  e = bag_error([&] { read_bag_laser_log(file, o); });
  EXPECT_NE(e.find("expected different scan and odometry topics"), std::string::npos) << e;
  o.odom_topic = "/tf_static";
  e = bag_error([&] { read_bag_laser_log(file, o); });
  EXPECT_NE(e.find("(--odom-topic): expected messages of type nav_msgs/Odometry or "
                   "geometry_msgs/PoseStamped"),
            std::string::npos)
      << e;
}

TEST(Bag, TimeRunningBackwardsNamesTopicAndMessage) {
  const std::string e = bag_error([] { read_bag_laser_log(kBagDir / "backwards.mcap"); });
  EXPECT_NE(e.find("backwards.mcap: topic '/scan' message 20: header.stamp"), std::string::npos)
      << e;
  EXPECT_NE(e.find("runs backwards"), std::string::npos) << e;
}

TEST(Bag, TruncatedOrCorruptFilesAreRefused) {
  for (const std::string file :
       {"intel-zstd.mcap", "intel-lz4.mcap", "intel-plain.mcap",
        "intel-rosbag2/intel-rosbag2_0.db3", "intel.bag", "intel-lz4.bag", "intel-bz2.bag"}) {
    const std::string bytes = bag_bytes(file);
    ASSERT_GT(bytes.size(), 1000u);
    // Cut anywhere, and one byte changed inside the first chunk (or the database's pages).
    std::vector<std::string> bad;
    for (std::size_t cut : {std::size_t{20}, bytes.size() / 3, bytes.size() / 2, bytes.size() - 1})
      bad.push_back(bytes.substr(0, cut));
    std::string flipped = bytes;
    flipped[300] = static_cast<char>(flipped[300] ^ 0x5a);
    if (file.ends_with(".mcap")) bad.push_back(flipped);
    for (std::size_t i = 0; i < bad.size(); ++i) {
      SCOPED_TRACE(file + " case " + std::to_string(i));
      const std::string e = bag_error([&] { bag_laser_log(parse_bag(bad[i], file)); });
      EXPECT_NE(e.find(file), std::string::npos) << e;
    }
  }
  EXPECT_NE(bag_error([] { parse_bag("FLASER 1 2 3", "x.log"); })
                .find("x.log: expected a ROS bag (an MCAP file, a rosbag2 SQLite file or a ROS 1 "
                      "bag of format 2.0), got a file that starts with 'FLASER 1 2 3'"),
            std::string::npos);
  EXPECT_NE(bag_error([] { read_bag(kBagDir / "missing.mcap"); }).find("no such file"),
            std::string::npos);
}

/// Appends `v` big-endian, after zero padding to its size from the CDR header's end (byte 4).
template <typename T>
void bag_put_big_endian(std::string& out, T v) {
  while ((out.size() - 4) % sizeof(T) != 0) out.push_back('\0');
  const auto bits =
      std::bit_cast<std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>>(v);
  for (std::size_t i = sizeof(T); i-- > 0;)
    out.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
}

TEST(Bag, BigEndianCdrIsReadToo) {
  // A geometry_msgs/PoseStamped in big-endian CDR (encapsulation 00 00), written by hand.
  std::string m("\0\0\0\0", 4);
  bag_put_big_endian<std::int32_t>(m, 12);
  bag_put_big_endian<std::uint32_t>(m, 500000000u);
  bag_put_big_endian<std::uint32_t>(m, 4u);
  m.append("map", 4);  // with its NUL
  for (double v : {1.5, -2.25, 0.0, 0.0, 0.0, std::sin(0.3), std::cos(0.3)})
    bag_put_big_endian<double>(m, v);
  const BagPoseMessage p = decode_pose_stamped(m, BagEncoding::kCdr, "be");
  EXPECT_EQ(p.header.time, 12.5);
  EXPECT_EQ(p.header.frame_id, "map");
  EXPECT_EQ(p.pose(0), 1.5);
  EXPECT_EQ(p.pose(1), -2.25);
  EXPECT_NEAR(p.pose(2), 0.6, 1e-15);
  // The same bytes cut short, or with a stamp's nanoseconds of 1e9 or more.
  EXPECT_NE(bag_error([&] {
              decode_pose_stamped(m.substr(0, m.size() - 1), BagEncoding::kCdr, "be");
            }).find("be: byte"),
            std::string::npos);
  std::string late = m;
  late[8] = static_cast<char>(0x7f);
  EXPECT_NE(bag_error([&] {
              decode_pose_stamped(late, BagEncoding::kCdr, "be");
            }).find("header.stamp.nanosec: expected less than 1e9"),
            std::string::npos);
}

TEST(Bag, MessagesOfAnotherTypeAreRefusedByTheirDecoder) {
  const BagContents bag = read_bag(kBagDir / "intel-plain.mcap", {"/odom"});
  ASSERT_FALSE(bag.messages.empty());
  const std::string& odom = bag.messages.front().data;
  std::string e = bag_error([&] { decode_laser_scan(odom, BagEncoding::kCdr, "m"); });
  EXPECT_EQ(e.find("m: "), 0u) << e;
  e = bag_error([&] { decode_pose_stamped(odom, BagEncoding::kCdr, "m"); });
  EXPECT_NE(e.find("expected a geometry_msgs/PoseStamped message of"), std::string::npos) << e;
  e = bag_error([&] { decode_odometry(odom.substr(0, odom.size() - 8), BagEncoding::kCdr, "m"); });
  EXPECT_NE(e.find("a truncated message"), std::string::npos) << e;
  e = bag_error(
      [&] { decode_odometry(std::string_view("\x02\x00\x00\x00", 4), BagEncoding::kCdr, "m"); });
  EXPECT_NE(e.find("expected a plain CDR message"), std::string::npos) << e;
}

}  // namespace
}  // namespace implicit::robot
