// The four message types of robot/bag.hpp, from ROS 2's CDR or ROS 1's serialisation. Both are
// the fields in order; CDR starts with a 4-byte encapsulation header (byte 1: 0 big-endian,
// 1 little-endian), aligns each number to its size from the end of that header, ends strings with
// a NUL counted in their length and stamps time as int32 sec + uint32 nanosec. ROS 1 is
// little-endian, unaligned, has strings without the NUL and a header with a uint32 seq first.
#include <cmath>
#include <cstring>

#include "bag_formats.hpp"

namespace implicit::robot {
namespace {

class MessageReader {
 public:
  MessageReader(std::string_view data, BagEncoding e, std::string_view where)
      : data_(data), where_(where), cdr_(e == BagEncoding::kCdr) {
    if (!cdr_) return;
    if (data.size() < 4)
      throw ParseError(fmt::format("{}: expected a CDR message (4-byte header first), got {} bytes",
                                   where, data.size()));
    if (data[0] != 0 || (data[1] != 0 && data[1] != 1))
      throw ParseError(fmt::format(
          "{}: expected a plain CDR message (encapsulation 00 00 or "
          "00 01), got {:02x} {:02x}",
          where, static_cast<unsigned char>(data[0]), static_cast<unsigned char>(data[1])));
    big_endian_ = data[1] == 0;
    pos_ = origin_ = 4;
  }

  double f64(std::string_view what) { return std::bit_cast<double>(number<std::uint64_t>(what)); }
  double f32(std::string_view what) {
    return static_cast<double>(std::bit_cast<float>(number<std::uint32_t>(what)));
  }
  std::uint32_t u32(std::string_view what) { return number<std::uint32_t>(what); }

  /// A sequence's length, checked against the bytes left for `element_bytes` each.
  std::size_t count(std::string_view what, std::size_t element_bytes) {
    const std::uint32_t n = u32(what);
    if (element_bytes > 0 && n > (data_.size() - pos_) / element_bytes)
      fail(fmt::format("{}: {} elements of {} bytes, with {} bytes left (a corrupt message?)", what,
                       n, element_bytes, data_.size() - pos_));
    return n;
  }

  std::string str(std::string_view what) {
    const std::size_t n = count(what, 1);
    std::string_view s = take(n, what);
    if (cdr_ && n > 0) {  // the NUL is part of the length
      if (s.back() != '\0') fail(fmt::format("{}: expected a string ending in NUL", what));
      s.remove_suffix(1);
    }
    return std::string(s);
  }

  BagStamp header() {
    if (!cdr_) u32("header.seq");
    BagStamp h;
    const double sec = cdr_
                           ? static_cast<double>(static_cast<std::int32_t>(u32("header.stamp.sec")))
                           : static_cast<double>(u32("header.stamp.sec"));
    const std::uint32_t ns = u32("header.stamp.nanosec");
    if (ns >= 1000000000u)
      fail(fmt::format("header.stamp.nanosec: expected less than 1e9, got {}", ns));
    h.time = sec + 1e-9 * static_cast<double>(ns);
    h.frame_id = str("header.frame_id");
    return h;
  }

  void skip_f64(std::size_t n, std::string_view what) {
    for (std::size_t i = 0; i < n; ++i) f64(what);
  }

  /// Every byte read: CDR may pad the end to a multiple of 4, nothing more.
  void finish(std::string_view type) const {
    const std::size_t left = data_.size() - pos_;
    if (left > (cdr_ ? 3u : 0u))
      throw ParseError(
          fmt::format("{}: expected a {} message of {} bytes, got {} bytes (the topic's "
                      "type is another?)",
                      where_, type, pos_, data_.size()));
  }

  [[noreturn]] void fail(std::string_view what) const {
    throw ParseError(fmt::format("{}: byte {} of the message: {}", where_, pos_, what));
  }

 private:
  std::string_view take(std::size_t n, std::string_view what) {
    if (n > data_.size() - pos_)
      fail(
          fmt::format("expected {} ({} bytes), got only {} bytes (a truncated message, or the "
                      "topic's type is another?)",
                      what, n, data_.size() - pos_));
    const std::string_view s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }

  template <typename T>
  T number(std::string_view what) {
    if (cdr_) {  // aligned to its size from the end of the encapsulation header
      const std::size_t misalign = (pos_ - origin_) % sizeof(T);
      if (misalign != 0) take(sizeof(T) - misalign, what);
    }
    const std::string_view b = take(sizeof(T), what);
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t k = big_endian_ ? sizeof(T) - 1 - i : i;
      v |= static_cast<T>(static_cast<T>(static_cast<unsigned char>(b[i])) << (8 * k));
    }
    return v;
  }

  std::string_view data_;
  std::string_view where_;
  bool cdr_ = true;
  bool big_endian_ = false;
  std::size_t pos_ = 0, origin_ = 0;
};

double yaw_of(double x, double y, double z, double w) {
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

/// geometry_msgs/Pose: position x y z, orientation x y z w; the planar pose.
Pose read_pose(MessageReader& r) {
  const double px = r.f64("pose.position.x"), py = r.f64("pose.position.y");
  r.f64("pose.position.z");
  const double qx = r.f64("pose.orientation.x"), qy = r.f64("pose.orientation.y");
  const double qz = r.f64("pose.orientation.z"), qw = r.f64("pose.orientation.w");
  return Pose(px, py, yaw_of(qx, qy, qz, qw));
}

}  // namespace

std::string bag_base_type(std::string_view type) {
  std::string t(type);
  const std::size_t k = t.find("/msg/");
  if (k != std::string::npos) t.erase(k, 4);
  return t;
}

BagScanMessage decode_laser_scan(std::string_view data, BagEncoding e, std::string_view where) {
  MessageReader r(data, e, where);
  BagScanMessage m;
  m.header = r.header();
  LaserScan& s = m.scan;
  s.time = m.header.time;
  s.angle_min = r.f32("angle_min");
  r.f32("angle_max");
  s.angle_increment = r.f32("angle_increment");
  r.f32("time_increment");
  r.f32("scan_time");
  s.range_min = r.f32("range_min");
  s.range_max = r.f32("range_max");
  s.ranges.resize(r.count("ranges", 4));
  for (double& v : s.ranges) v = r.f32("ranges");
  const std::size_t n = r.count("intensities", 4);
  for (std::size_t i = 0; i < n; ++i) r.f32("intensities");
  r.finish("sensor_msgs/LaserScan");
  return m;
}

BagPoseMessage decode_odometry(std::string_view data, BagEncoding e, std::string_view where) {
  MessageReader r(data, e, where);
  BagPoseMessage m;
  m.header = r.header();
  m.child_frame_id = r.str("child_frame_id");
  m.pose = read_pose(r);
  r.skip_f64(36, "pose.covariance");
  m.tv = r.f64("twist.linear.x");
  r.skip_f64(4, "twist.linear.y .. twist.angular.y");
  m.rv = r.f64("twist.angular.z");
  r.skip_f64(36, "twist.covariance");
  r.finish("nav_msgs/Odometry");
  return m;
}

BagPoseMessage decode_pose_stamped(std::string_view data, BagEncoding e, std::string_view where) {
  MessageReader r(data, e, where);
  BagPoseMessage m;
  m.header = r.header();
  m.pose = read_pose(r);
  r.finish("geometry_msgs/PoseStamped");
  return m;
}

std::vector<BagTransform> decode_tf_message(std::string_view data, BagEncoding e,
                                            std::string_view where) {
  MessageReader r(data, e, where);
  // Each transform takes at least a header and seven numbers: a bound on the count.
  std::vector<BagTransform> out(r.count("transforms", 8 + 4 + 7 * 8));
  for (BagTransform& t : out) {
    t.header = r.header();
    t.child_frame_id = r.str("child_frame_id");
    for (double& v : t.translation) v = r.f64("transform.translation");
    for (double& v : t.rotation) v = r.f64("transform.rotation");
  }
  r.finish("tf2_msgs/TFMessage");
  return out;
}

}  // namespace implicit::robot
