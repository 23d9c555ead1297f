// implicit.data.read_bag: a ROS bag (robot/bag.hpp) as the dict implicit.laser.read_carmen gives,
// with the bag's odometry, mount and frames.

#include <string>

#include "common.hpp"
#include "implicit/robot/bag.hpp"
#include "laser.hpp"

namespace implicit::python {
namespace {

/// A str naming a topic or frame; None gives `fallback`.
std::string bag_name_arg(const py::handle& o, const std::string& name,
                         const std::string& fallback) {
  if (o.is_none()) return fallback;
  if (!py::isinstance<py::str>(o))
    throw InvalidArgument(fmt::format("{}: expected a str, got {}", name, type_name(o)));
  const std::string s = o.cast<std::string>();
  require(!s.empty(), "{}: expected a name, got an empty str", name);
  return s;
}

py::dict bag_dict(const robot::BagLaserLog& b) {
  py::dict d = laser::carmen_log_dict(b.log);
  const auto n = static_cast<py::ssize_t>(b.log.odometry.size());
  py::array_t<double> times(n), poses({n, py::ssize_t{3}}), tv(n), rv(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    const auto& o = b.log.odometry[static_cast<std::size_t>(k)];
    times.mutable_at(k) = o.time;
    for (py::ssize_t j = 0; j < 3; ++j) poses.mutable_at(k, j) = o.pose(j);
    tv.mutable_at(k) = o.tv;
    rv.mutable_at(k) = o.rv;
  }
  py::dict odometry;
  odometry["times"] = times;
  odometry["poses"] = poses;
  odometry["tv"] = tv;
  odometry["rv"] = rv;
  d["odometry"] = odometry;
  py::array_t<double> mount(3);
  mount.mutable_at(0) = b.mount.x;
  mount.mutable_at(1) = b.mount.y;
  mount.mutable_at(2) = b.mount.yaw;
  d["mount"] = mount;
  d["mount_from_tf"] = b.mount_from_tf;
  d["base_frame"] = b.base_frame;
  d["laser_frame"] = b.laser_frame;
  d["scans_outside_odometry"] = b.scans_outside_odometry;
  return d;
}

}  // namespace

void init_bag(py::module_& m) {
  m.def(
      "read_bag",
      [](const py::object& path, const py::object& scan_topic, const py::object& odom_topic,
         const py::object& base_frame, const py::object& laser_frame) {
        robot::BagOptions o;
        const auto file = path_arg(path, "path");
        o.scan_topic = bag_name_arg(scan_topic, "scan_topic", o.scan_topic);
        o.odom_topic = bag_name_arg(odom_topic, "odom_topic", o.odom_topic);
        o.base_frame = bag_name_arg(base_frame, "base_frame", "");
        o.laser_frame = bag_name_arg(laser_frame, "laser_frame", "");
        return bag_dict(robot::read_bag_laser_log(file, o));
      },
      py::arg("path"), py::arg("scan_topic") = py::none(), py::arg("odom_topic") = py::none(),
      py::arg("base_frame") = py::none(), py::arg("laser_frame") = py::none(),
      "Reads a ROS bag (MCAP, rosbag2 SQLite file or folder, ROS 1 bag; docs/formats.md) as the "
      "dict of implicit.laser.read_carmen (laser_poses, odometry_poses, times, ranges, "
      "angle_min, angle_increment, range_min, range_max, lines, source), plus odometry (a dict "
      "of times, poses (M, 3), tv, rv), mount (x, y, yaw of the laser on the robot), "
      "mount_from_tf, base_frame, laser_frame and scans_outside_odometry. scan_topic defaults to "
      "/scan, odom_topic to /odom, the frames to the messages'. A malformed bag raises "
      "implicit.ParseError naming the file, topic and message.");
}

}  // namespace implicit::python
