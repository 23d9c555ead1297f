#include "implicit/robot/scan_simulation.hpp"

#include <algorithm>
#include <cmath>

#include "implicit/core/error.hpp"

namespace implicit::robot {

void ScanSimulationOptions::validate() const {
  require(beams >= 1 && beams <= 100000, "scan simulation: expected 1 to 100000 beams, got {}",
          beams);
  require(field_of_view > 0 && field_of_view <= 2.0 * kPi,
          "scan simulation: expected a field of view in (0, 2 pi] rad, got {}", field_of_view);
  require(range_min >= 0 && range_min < range_max && std::isfinite(range_max),
          "scan simulation: expected 0 <= range_min < range_max < infinity, got {} and {}",
          range_min, range_max);
  require(range_std >= 0 && std::isfinite(range_std),
          "scan simulation: expected a non-negative range noise, got {}", range_std);
}

LaserScan simulate_scan(const OccupancyGrid& grid, const Pose& robot_pose, const LaserMount& mount,
                        const ScanSimulationOptions& options, Rng& rng) {
  options.validate();
  require(robot_pose.allFinite(), "scan simulation: expected a finite pose");
  require(!grid.empty(), "scan simulation: expected a map, got an empty grid");
  LaserScan scan;
  scan.range_min = options.range_min;
  scan.range_max = options.range_max;
  // A full circle would repeat the first beam at the end: n beams split 2 pi in n parts.
  const bool full = options.field_of_view >= 2.0 * kPi - 1e-12;
  const int n = options.beams;
  scan.angle_increment =
      n == 1 ? 1.0 : options.field_of_view / static_cast<double>(full ? n : n - 1);
  scan.angle_min = n == 1 ? 0.0 : -0.5 * options.field_of_view;
  const Pose s = sensor_pose(robot_pose, mount);
  scan.ranges.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = s(2) + scan.bearing(static_cast<std::size_t>(i));
    const double r = cast_ray(grid, s.head<2>(), a, options.range_max);
    const double noise = rng.normal();  // drawn for every beam: the stream does not depend on hits
    if (r >= options.range_max) {
      scan.ranges[static_cast<std::size_t>(i)] = options.range_max;
      continue;
    }
    const double noisy = r + options.range_std * noise;
    scan.ranges[static_cast<std::size_t>(i)] =
        std::clamp(noisy, options.range_min, std::nextafter(options.range_max, 0.0));
  }
  return scan;
}

}  // namespace implicit::robot
