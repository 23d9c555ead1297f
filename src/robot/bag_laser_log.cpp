// A bag's scans, odometry and laser mount as the in-memory CARMEN log (robot/bag.hpp), and that
// log as CARMEN text.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <optional>

#include <Eigen/Geometry>

#include "bag_formats.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::robot {
namespace {

// A laser tilted by more than this out of the plane does not scan the plane (about 6 degrees: a
// 30 m beam would then sweep 3 m above or below the robot's plane).
constexpr double kMaxLaserTilt = 0.1;  // [rad]

std::string topics_listed(const BagContents& bag) {
  std::string s;
  for (const BagTopic& t : bag.topics)
    s += fmt::format("{}{} ({})", s.empty() ? "" : ", ", printable(t.name, 60),
                     printable(t.type, 60));
  return s.empty() ? "none" : s;
}

/// The topic `name` (the option `flag`), of one of the `types`; otherwise a ParseError.
std::size_t chosen_topic(const BagContents& bag, const std::string& name, std::string_view flag,
                         std::initializer_list<std::string_view> types) {
  const std::size_t k = bag.find_topic(name);
  if (k == bag.topics.size())
    throw ParseError(fmt::format("{}: expected topic '{}' ({}), got no such topic; the bag has: {}",
                                 bag.source, printable(name), flag, topics_listed(bag)));
  const std::string type = bag_base_type(bag.topics[k].type);
  std::string expected;
  for (std::string_view t : types) {
    if (type == t) return k;
    expected += fmt::format("{}{}", expected.empty() ? "" : " or ", t);
  }
  throw ParseError(fmt::format("{}: topic '{}' ({}): expected messages of type {}, got '{}'",
                               bag.source, printable(name), flag, expected,
                               printable(bag.topics[k].type)));
}

std::string where_of(const BagContents& bag, std::size_t topic, std::size_t index) {
  return fmt::format("{}: topic '{}' message {}", bag.source, printable(bag.topics[topic].name),
                     index);
}

/// A time that runs backwards on a topic is a broken recording (or a clock reset).
void require_forward(double previous, double t, const std::string& where) {
  if (t < previous)
    throw ParseError(
        fmt::format("{}: header.stamp {:.9f} s runs backwards (the message before "
                    "has {:.9f} s)",
                    where, t, previous));
}

using Transform3 = Eigen::Isometry3d;

Transform3 transform_of(const BagTransform& t) {
  Eigen::Quaterniond q(t.rotation[3], t.rotation[0], t.rotation[1], t.rotation[2]);
  if (!(q.norm() > 1e-9)) q = Eigen::Quaterniond::Identity();  // also NaN
  Transform3 m = Transform3::Identity();
  m.linear() = q.normalized().toRotationMatrix();
  m.translation() = Eigen::Vector3d(t.translation[0], t.translation[1], t.translation[2]);
  return m;
}

/// Every frame's parent and transform, /tf_static first, then the first one /tf gives.
struct FrameTree {
  std::map<std::string, std::pair<std::string, Transform3>> parent;

  void add(const std::vector<BagTransform>& list) {
    for (const BagTransform& t : list)
      if (!parent.contains(t.child_frame_id))
        parent[t.child_frame_id] = {t.header.frame_id, transform_of(t)};
  }

  /// base -> child by walking up from child; nullopt when base is not above it.
  std::optional<Transform3> lookup(const std::string& base, const std::string& child) const {
    Transform3 m = Transform3::Identity();
    std::string f = child;
    for (std::size_t hops = 0; hops <= parent.size(); ++hops) {
      if (f == base) return m;
      const auto p = parent.find(f);
      if (p == parent.end()) return std::nullopt;
      m = p->second.second * m;
      f = p->second.first;
    }
    return std::nullopt;  // a cycle
  }
};

/// The pose on `odometry` (sorted by time) at time t, linear between the two around it;
/// nullopt outside their span.
std::optional<Pose> pose_at(const std::vector<CarmenLog::Odometry>& odometry, double t) {
  if (odometry.empty() || t < odometry.front().time || t > odometry.back().time)
    return std::nullopt;
  const auto b =
      std::lower_bound(odometry.begin(), odometry.end(), t,
                       [](const CarmenLog::Odometry& o, double v) { return o.time < v; });
  if (b->time == t || b == odometry.begin()) return b->pose;
  const auto a = b - 1;
  const double w = (t - a->time) / (b->time - a->time);
  Pose p;
  p.head<2>() = a->pose.head<2>() + w * (b->pose.head<2>() - a->pose.head<2>());
  p(2) = a->pose(2) + w * wrap_angle(b->pose(2) - a->pose(2));
  return p;
}

/// REP 117's NaN, +inf and -inf, and readings outside [range_min, range_max]: no return.
void sanitise_readings(LaserScan& s) {
  for (double& r : s.ranges)
    if (!(r >= s.range_min && r <= s.range_max)) r = s.range_max;
  s.range_min = 0.0;
}

void read_mount(const BagContents& bag, BagLaserLog& out) {
  FrameTree tree;
  for (const char* name : {"/tf_static", "/tf"}) {
    const std::size_t k = bag.find_topic(name);
    if (k == bag.topics.size() || bag_base_type(bag.topics[k].type) != "tf2_msgs/TFMessage")
      continue;
    std::size_t index = 0;
    for (const BagMessage& m : bag.messages)
      if (m.topic == k)
        tree.add(decode_tf_message(m.data, bag.topics[k].encoding, where_of(bag, k, index++)));
  }
  const auto t = tree.lookup(out.base_frame, out.laser_frame);
  if (!t) return;
  const Eigen::Matrix3d r = t->linear();
  const double tilt = std::acos(std::clamp(r(2, 2), -1.0, 1.0));
  if (tilt > kMaxLaserTilt)
    throw ParseError(fmt::format(
        "{}: the transform {} -> {} tilts the laser {:.3f} rad out of the plane (expected at "
        "most {} rad: a planar laser, upright)",
        bag.source, printable(out.base_frame), printable(out.laser_frame), tilt, kMaxLaserTilt));
  out.mount = LaserMount{t->translation()(0), t->translation()(1), std::atan2(r(1, 0), r(0, 0))};
  out.mount_from_tf = true;
}

std::vector<CarmenLog::Odometry> read_bag_odometry(const BagContents& bag, std::size_t topic,
                                                   std::string& child_frame) {
  const bool odometry = bag_base_type(bag.topics[topic].type) == "nav_msgs/Odometry";
  std::vector<CarmenLog::Odometry> out;
  std::size_t index = 0;
  for (const BagMessage& m : bag.messages) {
    if (m.topic != topic) continue;
    const std::string where = where_of(bag, topic, index++);
    const BagPoseMessage p = odometry
                                 ? decode_odometry(m.data, bag.topics[topic].encoding, where)
                                 : decode_pose_stamped(m.data, bag.topics[topic].encoding, where);
    if (!p.pose.allFinite() || !std::isfinite(p.tv) || !std::isfinite(p.rv))
      throw ParseError(fmt::format("{}: expected a finite pose and twist, got ({}, {}, {})", where,
                                   p.pose(0), p.pose(1), p.pose(2)));
    if (!out.empty()) require_forward(out.back().time, p.header.time, where);
    if (child_frame.empty()) child_frame = p.child_frame_id;
    out.push_back({p.header.time, p.pose, p.tv, p.rv});
  }
  if (out.empty())
    throw ParseError(fmt::format("{}: topic '{}' (--odom-topic): expected messages, got none",
                                 bag.source, printable(bag.topics[topic].name)));
  return out;
}

}  // namespace

void BagOptions::validate() const {
  require(!scan_topic.empty(), "bag: expected a scan topic (--scan-topic), got an empty name");
  require(!odom_topic.empty(), "bag: expected an odometry topic (--odom-topic), got an empty name");
  require(scan_topic != odom_topic,
          "bag: expected different scan and odometry topics, got '{}' for both",
          printable(scan_topic));
}

BagLaserLog read_bag_laser_log(const std::filesystem::path& path, const BagOptions& options) {
  options.validate();
  return bag_laser_log(
      read_bag(path, {options.scan_topic, options.odom_topic, "/tf_static", "/tf"}), options);
}

BagLaserLog bag_laser_log(const BagContents& bag, const BagOptions& options) {
  options.validate();
  const std::size_t scan_topic =
      chosen_topic(bag, options.scan_topic, "--scan-topic", {"sensor_msgs/LaserScan"});
  const std::size_t odom_topic = chosen_topic(bag, options.odom_topic, "--odom-topic",
                                              {"nav_msgs/Odometry", "geometry_msgs/PoseStamped"});
  BagLaserLog out;
  CarmenLog& log = out.log;
  log.source = bag.source;
  std::string child_frame;
  log.odometry = read_bag_odometry(bag, odom_topic, child_frame);
  out.base_frame = !options.base_frame.empty() ? options.base_frame
                   : !child_frame.empty()      ? child_frame
                                               : std::string("base_link");
  std::vector<BagScanMessage> scans;
  for (const BagMessage& m : bag.messages) {
    if (m.topic != scan_topic) continue;
    const std::string where = where_of(bag, scan_topic, scans.size());
    scans.push_back(decode_laser_scan(m.data, bag.topics[scan_topic].encoding, where));
    if (scans.size() > 1)
      require_forward(scans[scans.size() - 2].scan.time, scans.back().scan.time, where);
  }
  if (scans.empty())
    throw ParseError(fmt::format("{}: topic '{}' (--scan-topic): expected messages, got none",
                                 bag.source, printable(options.scan_topic)));
  out.laser_frame =
      !options.laser_frame.empty() ? options.laser_frame : scans.front().header.frame_id;
  read_mount(bag, out);
  const Pose mount(out.mount.x, out.mount.y, out.mount.yaw);
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const std::optional<Pose> pose = pose_at(log.odometry, scans[k].scan.time);
    if (!pose) {
      ++out.scans_outside_odometry;
      continue;
    }
    LaserScan& s = scans[k].scan;
    sanitise_readings(s);
    s.validate(where_of(bag, scan_topic, k));
    log.scans.push_back(std::move(s));
    log.odometry_poses.push_back(*pose);
    log.laser_poses.push_back(compose(*pose, mount));
    log.scan_lines.push_back(k);
    log.rear.push_back(false);
  }
  log.lines = bag.messages.size();
  if (log.scans.empty())
    throw ParseError(fmt::format(
        "{}: expected scans on '{}' within the time span of the odometry on '{}' ({:.3f} to "
        "{:.3f} s), got none there (the scans from {:.3f} to {:.3f} s)",
        bag.source, printable(options.scan_topic), printable(options.odom_topic),
        log.odometry.front().time, log.odometry.back().time, scans.front().scan.time,
        scans.back().scan.time));
  return out;
}

std::string carmen_log_text(const CarmenLog& log) {
  std::string text = fmt::format(
      "# {} as a CARMEN log: ROBOTLASER1 (the scan, the laser's and the robot's pose) and ODOM\n",
      printable(log.source));
  auto out = std::back_inserter(text);
  std::size_t o = 0;
  auto odom_line = [&](const CarmenLog::Odometry& d) {
    fmt::format_to(out, "ODOM {} {} {} {} {} 0 {} bag {}\n", d.pose(0), d.pose(1), d.pose(2), d.tv,
                   d.rv, d.time, d.time);
  };
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    const LaserScan& s = log.scans[k];
    for (; o < log.odometry.size() && log.odometry[o].time <= s.time; ++o)
      odom_line(log.odometry[o]);
    const double fov = s.angle_increment * static_cast<double>(s.size() - 1);
    fmt::format_to(out, "ROBOTLASER1 0 {} {} {} {} 0 0 {}", s.angle_min, fov, s.angle_increment,
                   s.range_max, s.size());
    for (double r : s.ranges) fmt::format_to(out, " {}", r);
    const Pose& l = log.laser_poses[k];
    const Pose& p = log.odometry_poses[k];
    fmt::format_to(out, " 0 {} {} {} {} {} {} 0 0 0 0 0 {} bag {}\n", l(0), l(1), l(2), p(0), p(1),
                   p(2), s.time, s.time);
  }
  for (; o < log.odometry.size(); ++o) odom_line(log.odometry[o]);
  return text;
}

}  // namespace implicit::robot
