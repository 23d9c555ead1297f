#pragma once
// Readers for ROS bags, without a ROS installation: rosbag2's SQLite files (.db3, alone or in their
// folder with metadata.yaml), MCAP files (.mcap: chunks uncompressed, zstd or lz4) and ROS 1 bags
// (format 2.0: chunks uncompressed, bz2 or lz4). They turn a robot's recording into the same
// in-memory log as a CARMEN file (carmen.hpp), which the laser pipeline runs on.
//
//   robot::BagOptions o;                  // /scan, /odom; the frames from the messages
//   robot::BagLaserLog b = robot::read_bag_laser_log("run.mcap", o);
//   const robot::CarmenLog& log = b.log;  // scans, laser poses, odometry poses, odometry
//
// Three layers:
//  1. read_bag: the file's topics and the serialised messages of the topics asked for, in receive
//     order (the format from the file's first bytes, any name);
//  2. decode_*: the four message types read here, from ROS 2's CDR (either byte order) or ROS 1's
//     serialisation: sensor_msgs/LaserScan, nav_msgs/Odometry, geometry_msgs/PoseStamped and
//     tf2_msgs/TFMessage (/tf and /tf_static);
//  3. read_bag_laser_log: the scans of scan_topic, each with the robot's pose on odom_topic
//     (nav_msgs/Odometry or geometry_msgs/PoseStamped) interpolated at the scan's stamp (linear in
//     x, y and the wrapped heading; scans outside the odometry's time span are left out and
//     counted), and the laser's mount: the transform base_frame -> laser_frame composed from the
//     /tf_static messages (then /tf's first), projected on the plane.
//
// The in-memory log follows CARMEN's layout: odometry_poses[k] is the robot's pose at scan k,
// laser_poses[k] that pose composed with the mount; the laser pipeline takes the first as the
// reference of the semi-synthetic protocol (experiments/laser_mcl.hpp). Readings that measure
// nothing (REP 117: NaN invalid, +inf no return, -inf too close, and any reading below range_min
// or above range_max) become range_max, "no return", and range_min becomes 0: so the log written
// by write_carmen_log reads back as the same log, bit for bit.
//
// Refused, with a ParseError naming the file and, where it applies, the topic and the message's
// index on it (0-based, in receive order): a file of no bag format; a truncated or corrupt file
// (a record that runs past the end, a CRC that does not match, a chunk that does not decompress
// to its stated size); a chosen topic that is missing (the topics present are listed) or has a
// type other than those above; a message shorter or longer than its type; a stamp that runs
// backwards on the scan or odometry topic; a scan that fails LaserScan::validate. A mount that
// tilts the laser out of the plane (more than 0.1 rad of roll or pitch) is refused too: the scans
// would not be planar.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "implicit/robot/carmen.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// How a topic's messages are serialised: ROS 2's CDR or ROS 1's format.
enum class BagEncoding { kCdr, kRos1 };

struct BagTopic {
  std::string name;  ///< e.g. "/scan"
  std::string
      type;  ///< as the bag names it: "sensor_msgs/msg/LaserScan" or "sensor_msgs/LaserScan"
  BagEncoding encoding = BagEncoding::kCdr;
};

struct BagMessage {
  std::size_t topic = 0;     ///< index into BagContents::topics
  std::int64_t time_ns = 0;  ///< the recorder's receive time [ns]
  std::string data;          ///< the serialised message
};

struct BagContents {
  std::string source;                ///< the file name, for messages
  std::string format;                ///< "rosbag2 SQLite", "MCAP" or "ROS 1 bag"
  std::vector<BagTopic> topics;      ///< every topic of the file
  std::vector<BagMessage> messages;  ///< of the topics asked for, by receive time (stable)

  /// Index of the topic named `name`, or topics.size() when there is none.
  std::size_t find_topic(std::string_view name) const;
};

/// True when `path` is a bag: a folder with a metadata.yaml, or a file that starts as a SQLite
/// database, an MCAP file or a ROS 1 bag does.
bool is_bag(const std::filesystem::path& path);

/// Reads a bag file or rosbag2 folder; keeps the messages of `topics` only (empty: all).
BagContents read_bag(const std::filesystem::path& path,
                     const std::vector<std::string>& topics = {});

/// Parses a bag held in memory (MCAP, ROS 1 or SQLite, told from the first bytes); `name` is
/// used in messages only.
BagContents parse_bag(std::string_view bytes, std::string_view name,
                      const std::vector<std::string>& topics = {});

// ---- messages
// -------------------------------------------------------------------------------------

struct BagStamp {
  double time = 0.0;  ///< header.stamp [s]
  std::string frame_id;
};

struct BagScanMessage {
  BagStamp header;
  LaserScan scan;  ///< time = header.stamp; readings as in the message (float32 widened)
};

struct BagPoseMessage {
  BagStamp header;
  std::string child_frame_id;  ///< Odometry's; empty for PoseStamped
  Pose pose = Pose::Zero();    ///< x, y and the yaw of the orientation
  double tv = 0.0, rv = 0.0;   ///< Odometry's twist.linear.x [m/s] and twist.angular.z [rad/s]
};

struct BagTransform {
  BagStamp header;  ///< frame_id: the parent frame
  std::string child_frame_id;
  double translation[3] = {0, 0, 0};  ///< x, y, z [m]
  double rotation[4] = {0, 0, 0, 1};  ///< quaternion x, y, z, w
};

/// Decoders of one serialised message; `where` (file, topic, index) prefixes their errors.
BagScanMessage decode_laser_scan(std::string_view data, BagEncoding e, std::string_view where);
BagPoseMessage decode_odometry(std::string_view data, BagEncoding e, std::string_view where);
BagPoseMessage decode_pose_stamped(std::string_view data, BagEncoding e, std::string_view where);
std::vector<BagTransform> decode_tf_message(std::string_view data, BagEncoding e,
                                            std::string_view where);

/// The message type without its package's "msg/" (ROS 2) part: "sensor_msgs/LaserScan".
std::string bag_base_type(std::string_view type);

// ---- the laser log
// -------------------------------------------------------------------------------

struct BagOptions {
  std::string scan_topic = "/scan";  ///< sensor_msgs/LaserScan
  std::string odom_topic = "/odom";  ///< nav_msgs/Odometry or geometry_msgs/PoseStamped
  std::string base_frame;   ///< empty: the odometry's child_frame_id (PoseStamped: "base_link")
  std::string laser_frame;  ///< empty: the first scan's header.frame_id
  void validate() const;
};

struct BagLaserLog {
  CarmenLog log;  ///< source = the bag; scan_lines = each scan's index on scan_topic
  LaserMount mount;
  bool mount_from_tf = false;  ///< false: no transform base_frame -> laser_frame, mount zero
  std::string base_frame, laser_frame;     ///< as used
  std::size_t scans_outside_odometry = 0;  ///< scans left out (no odometry around their stamp)
};

BagLaserLog read_bag_laser_log(const std::filesystem::path& path, const BagOptions& options = {});
/// The same from contents already read (the tests and the fuzz target).
BagLaserLog bag_laser_log(const BagContents& bag, const BagOptions& options = {});

/// The log as CARMEN text: ROBOTLASER1 lines (the scan's angles and range_max, the laser and
/// robot poses) and ODOM lines, every number written so that it reads back exactly.
std::string carmen_log_text(const CarmenLog& log);

}  // namespace implicit::robot
