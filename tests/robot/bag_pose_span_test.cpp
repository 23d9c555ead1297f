// Scans outside the time span of the pose topic (`implicit map --pose-topic`): a fixture bag whose
// /ground_truth (one geometry_msgs/PoseStamped at every scan's stamp) loses its first two and last
// three messages in memory leaves the scans stamped before its first and after its last pose out,
// counted, and gives the others the poses of the full topic.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "implicit/core/weights.hpp"
#include "implicit/robot/bag.hpp"

namespace implicit::robot {
namespace {

const std::filesystem::path kBagSpanDir =
    std::filesystem::path(IMPLICIT_SOURCE_DIR) / "tests" / "data" / "bags";

TEST(BagPoseSpan, ScansOutsideThePoseTopicAreLeftOutAndCounted) {
  BagOptions o;
  o.odom_topic = "/ground_truth";
  const std::vector<std::string> topics = {o.scan_topic, o.odom_topic, "/tf_static", "/tf"};
  const BagContents full = read_bag(kBagSpanDir / "intel-zstd.mcap", topics);
  const BagLaserLog all = bag_laser_log(full, o);
  ASSERT_EQ(all.log.scans.size(), 30u);
  ASSERT_EQ(all.scans_outside_odometry, 0u);

  // Drop pose messages 0, 1 and 27, 28, 29 (in receive order, which is stamp order here).
  const std::size_t pose_topic = full.find_topic(o.odom_topic);
  ASSERT_LT(pose_topic, full.topics.size());
  BagContents cut = full;
  cut.messages.clear();
  std::size_t seen = 0;
  for (const BagMessage& m : full.messages) {
    if (m.topic == pose_topic) {
      const std::size_t k = seen++;
      if (k < 2 || k >= 27) continue;
    }
    cut.messages.push_back(m);
  }
  ASSERT_EQ(seen, 30u);
  const BagLaserLog kept = bag_laser_log(cut, o);
  // Scans 0, 1 (before the first pose left, scan 2's) and 27..29 (after scan 26's) have no pose.
  EXPECT_EQ(kept.scans_outside_odometry, 5u);
  ASSERT_EQ(kept.log.scans.size(), 25u);
  for (std::size_t k = 0; k < 25; ++k) {
    EXPECT_EQ(kept.log.scans[k].time, all.log.scans[k + 2].time) << "scan " << k;
    EXPECT_EQ(kept.log.scan_lines[k], k + 2) << "scan " << k;
    // A scan at a pose's own stamp takes that pose (up to the interpolation's rounding).
    EXPECT_NEAR(
        (kept.log.odometry_poses[k].head<2>() - all.log.odometry_poses[k + 2].head<2>()).norm(),
        0.0, 1e-12)
        << "scan " << k;
    EXPECT_NEAR(wrap_angle(kept.log.odometry_poses[k](2) - all.log.odometry_poses[k + 2](2)), 0.0,
                1e-12)
        << "scan " << k;
  }
}

}  // namespace
}  // namespace implicit::robot
