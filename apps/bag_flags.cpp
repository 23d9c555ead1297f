// The ROS bag flags (bag_flags.hpp).
#include "bag_flags.hpp"

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::app {
namespace {

CLI::Validator bag_name_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty()) return "expected a name, got an empty one";
        return {};
      },
      "NAME");
}

}  // namespace

void add_bag_flags(CLI::App& sub, BagFlags& flags) {
  robot::BagOptions& o = flags.options;
  flags.given = {
      sub.add_option("--scan-topic", o.scan_topic,
                     "ROS bag as --data: the topic of the scans (sensor_msgs/LaserScan)")
          ->check(bag_name_validator())
          ->capture_default_str(),
      sub.add_option("--odom-topic", o.odom_topic,
                     "ROS bag as --data: the topic of the robot's pose, interpolated at each scan "
                     "(nav_msgs/Odometry or geometry_msgs/PoseStamped)")
          ->check(bag_name_validator())
          ->capture_default_str(),
      sub.add_option(
             "--base-frame", o.base_frame,
             "ROS bag as --data: the robot's frame (default: the odometry's child_frame_id, "
             "else base_link)")
          ->check(bag_name_validator()),
      sub.add_option("--laser-frame", o.laser_frame,
                     "ROS bag as --data: the laser's frame; its mount is the transform from the "
                     "robot's frame on /tf_static or /tf (default: the scans' frame_id)")
          ->check(bag_name_validator()),
  };
}

void require_bag_for_flags(const BagFlags& flags, const std::string& data,
                           std::string_view command) {
  for (const CLI::Option* f : flags.given)
    if (f->count() > 0)
      require(robot::is_bag(data),
              "{} {}: applies to a ROS bag as --data (an .mcap, .db3 or .bag file, or a rosbag2 "
              "folder), got '{}'",
              command, f->get_name(), printable(data));
}

}  // namespace implicit::app
