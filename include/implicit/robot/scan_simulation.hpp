#pragma once
// Laser scans ray-cast on an occupancy grid: synthetic data for tests, examples and
// `implicit simulate --map`.
//
//   ScanSimulationOptions o;              // 181 beams over 180 degrees, 30 m, 2 cm noise
//   LaserScan scan = simulate_scan(grid, pose, mount, o, rng);
//
// Each beam is cast from the sensor (cast_ray in occupancy_grid.hpp); a beam that hits nothing
// within range_max reads range_max (no return); a hit gets Gaussian noise of range_std,
// clamped to [range_min, range_max).

#include "implicit/core/rng.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

struct ScanSimulationOptions {
  int beams = 181;
  double field_of_view = kPi;  ///< [rad], centred on the sensor's x axis
  double range_min = 0.05;     ///< [m]
  double range_max = 30.0;     ///< [m]
  double range_std = 0.02;     ///< [m] noise of a hit
  void validate() const;
};

/// The sensor's pose in the world for robot pose x: x ⊕ mount.
inline Pose sensor_pose(const Pose& x, const LaserMount& mount) {
  return compose(x, Pose(mount.x, mount.y, mount.yaw));
}

LaserScan simulate_scan(const OccupancyGrid& grid, const Pose& robot_pose, const LaserMount& mount,
                        const ScanSimulationOptions& options, Rng& rng);

}  // namespace implicit::robot
