// Fuzz target: the ROS bag readers and message decoders (src/robot/bag*.cpp).
//
// An input that starts as a bag (MCAP, ROS 1 or SQLite magic) goes through parse_bag and, when it
// is accepted, bag_laser_log with the default topics; any other input is decoded as one message
// of each type, in CDR and in ROS 1's format. Properties checked on every input:
//  * each reader accepts it or throws ParseError / InvalidArgument (anything else is a finding:
//    another exception, a crash, a sanitizer report, a hang);
//  * an accepted bag is consistent: every message names one of its topics, in receive order;
//  * an accepted laser log has one pose of each kind and one index per scan, finite poses, valid
//    scans (LaserScan::validate) whose readings lie in [0, range_max], stamps that do not run
//    backwards, and its CARMEN text reads back with as many scans.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "implicit/core/error.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/carmen.hpp"
#include "scratch.hpp"

namespace {

using namespace implicit::robot;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "fuzz_bag: %s\n", what);
  std::abort();
}

void require_consistent(const BagContents& bag) {
  for (std::size_t i = 0; i < bag.messages.size(); ++i) {
    if (bag.messages[i].topic >= bag.topics.size()) fail("a message names no topic");
    if (i > 0 && bag.messages[i].time_ns < bag.messages[i - 1].time_ns)
      fail("messages out of receive order");
  }
}

void require_consistent(const BagLaserLog& b) {
  const CarmenLog& log = b.log;
  const std::size_t n = log.scans.size();
  if (n == 0) fail("a log without scans was accepted");
  if (log.laser_poses.size() != n || log.odometry_poses.size() != n || log.scan_lines.size() != n)
    fail("the per-scan vectors differ in length");
  for (std::size_t k = 0; k < n; ++k) {
    if (!log.laser_poses[k].allFinite() || !log.odometry_poses[k].allFinite())
      fail("a non-finite pose was accepted");
    const LaserScan& s = log.scans[k];
    s.validate("fuzz_bag");  // throws InvalidArgument: a finding here (not caught)
    if (k > 0 && s.time < log.scans[k - 1].time) fail("scan stamps run backwards");
    for (double r : s.ranges)
      if (!(r >= 0 && r <= s.range_max)) fail("a reading outside [0, range_max] was kept");
  }
  if (!std::isfinite(b.mount.x) || !std::isfinite(b.mount.y) || !std::isfinite(b.mount.yaw))
    fail("a non-finite mount");
  const CarmenLog back = parse_carmen(carmen_log_text(log), "fuzz_bag.log");
  if (back.scans.size() != n) fail("the CARMEN text lost scans");
}

template <typename F>
void decoded(F&& f) {
  try {
    f();
  } catch (const implicit::ParseError&) {
  } catch (const implicit::InvalidArgument&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = implicit::fuzz::as_text(data, size);
  const bool bag_magic = bytes.starts_with("\x89MCAP") || bytes.starts_with("#ROSBAG") ||
                         bytes.starts_with(std::string_view("SQLite format 3\0", 16));
  if (!bag_magic) {
    for (BagEncoding e : {BagEncoding::kCdr, BagEncoding::kRos1}) {
      decoded([&] { decode_laser_scan(bytes, e, "m"); });
      decoded([&] { decode_odometry(bytes, e, "m"); });
      decoded([&] { decode_pose_stamped(bytes, e, "m"); });
      decoded([&] { decode_tf_message(bytes, e, "m"); });
    }
    return 0;
  }
  BagContents bag;
  try {
    bag = parse_bag(bytes, "input.bag");
  } catch (const implicit::ParseError&) {
    return 0;
  } catch (const implicit::InvalidArgument&) {
    return 0;
  }
  require_consistent(bag);
  try {
    require_consistent(bag_laser_log(bag));
  } catch (const implicit::ParseError&) {
  }
  return 0;
}
