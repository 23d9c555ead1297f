#pragma once
// A planar laser scan: ranges at equally spaced bearings, in the sensor's own frame.
//
// Beam i points at bearing angle_min + i * angle_increment from the sensor's x axis,
// counter-clockwise (ROS sensor_msgs/LaserScan). A reading r >= range_max, or +infinity, means
// "no return" (nothing within range): it is not a distance to a wall. A reading below
// range_min is not a measurement either. NaN is refused (validate()): a reader turns a sensor's
// "invalid" into +infinity or drops the scan, and says so.
//
//   LaserScan scan;
//   scan.angle_min = -kPi / 2; scan.angle_increment = kPi / 180; scan.range_max = 81.9;
//   scan.ranges = {...};                                  // 180 beams from the right to the left
//   scan.validate("intel.log line 12");                   // throws InvalidArgument naming it
//
// The sensor's mounting on the robot (LaserMount) belongs to the observation model, not to the
// scan: a log records it once.

#include <cmath>
#include <cstddef>
#include <string_view>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

struct LaserScan {
  double time = 0.0;             ///< [s]
  double angle_min = 0.0;        ///< bearing of beam 0 in the sensor frame [rad]
  double angle_increment = 0.0;  ///< [rad], may be negative (a scan from left to right)
  double range_min = 0.0;        ///< [m] readings below are not measurements
  double range_max = 0.0;        ///< [m] readings at or above mean "no return"
  std::vector<double> ranges;    ///< [m]

  std::size_t size() const { return ranges.size(); }
  double bearing(std::size_t i) const {
    return angle_min + static_cast<double>(i) * angle_increment;
  }
  /// A reading that measures a distance to something (not "no return", not below range_min).
  bool is_hit(std::size_t i) const { return ranges[i] >= range_min && ranges[i] < range_max; }

  /// Throws InvalidArgument naming `where` unless the scan is usable: at least one beam, finite
  /// angles with a non-zero increment, 0 <= range_min < range_max < infinity, and no NaN or
  /// negative reading (+infinity is allowed: no return).
  void validate(std::string_view where) const {
    require(!ranges.empty(), "{}: expected a laser scan with at least one beam, got none", where);
    require(std::isfinite(angle_min) && std::isfinite(angle_increment) && angle_increment != 0,
            "{}: expected finite beam angles with a non-zero increment, got angle_min {} and "
            "increment {}",
            where, angle_min, angle_increment);
    require(std::isfinite(range_max) && range_min >= 0 && range_min < range_max,
            "{}: expected 0 <= range_min < range_max < infinity, got range_min {} and range_max {}",
            where, range_min, range_max);
    for (std::size_t i = 0; i < ranges.size(); ++i)
      require(!std::isnan(ranges[i]) && ranges[i] >= 0,
              "{}: beam {} has range {} (expected a non-negative number; +inf means no return)",
              where, i, ranges[i]);
  }
};

/// nav2's beam subsampling: of a scan's n beams, `used` (<= n) evenly spaced from the first to
/// the last; the index of the k-th of them. Every laser model selects its beams this way.
inline std::size_t evenly_spaced_beam(std::size_t k, std::size_t used, std::size_t n) {
  const double step = used > 1 ? static_cast<double>(n - 1) / static_cast<double>(used - 1) : 0.0;
  return static_cast<std::size_t>(std::lround(static_cast<double>(k) * step));
}

/// Where the laser sits on the robot: its pose (x forward [m], y left [m], yaw [rad]) in the
/// robot's frame. The end point of beam i at robot pose x is x ⊕ mount ⊕ (r cos b, r sin b).
struct LaserMount {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

}  // namespace implicit::robot
