#pragma once
// When grid SLAM integrates a scan into the maps: GMapping's linearUpdate / angularUpdate. A scan
// is integrated once the robot has moved linear_update metres, or turned angular_update radians,
// since the last scan it integrated; the scans between are not used. Integrating every scan
// would count the same walls again and again from nearly the same pose (the log-odds sum treats
// them as independent evidence), and would cost a map update per particle per scan.
//
//   slam::MapUpdateGate gate;                      // 1 m or 0.5 rad, GMapping's defaults
//   if (gate.due(last_integrated_pose, pose)) { /* weight, integrate, last = pose */ }
//
// The distance is the displacement between the two poses and the turn is their heading
// difference wrapped to [-pi, pi): GMapping sums the odometry increments instead, so a robot
// that goes back and forth (or turns one way then back) triggers an update here later than
// there. Zero thresholds make every scan due.

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"  // wrap_angle
#include "implicit/robot/types.hpp"

namespace implicit::slam {

struct MapUpdateGate {
  double linear_update = 1.0;   ///< [m] integrate after moving this far
  double angular_update = 0.5;  ///< [rad] or after turning this much

  /// Throws InvalidArgument naming the first threshold that is not finite and >= 0.
  void validate() const {
    require(std::isfinite(linear_update) && linear_update >= 0,
            "MapUpdateGate: expected linear_update >= 0 [m] and finite, got {}", linear_update);
    require(std::isfinite(angular_update) && angular_update >= 0,
            "MapUpdateGate: expected angular_update >= 0 [rad] and finite, got {}", angular_update);
  }

  /// Whether a scan taken at `now` is to be integrated, the last integrated one having been taken
  /// at `last_update`. Throws InvalidArgument for invalid thresholds or a non-finite pose.
  bool due(const robot::Pose& last_update, const robot::Pose& now) const {
    validate();
    require(last_update.allFinite(),
            "MapUpdateGate::due: expected a finite last_update pose, got ({}, {}, {})",
            last_update(0), last_update(1), last_update(2));
    require(now.allFinite(), "MapUpdateGate::due: expected a finite pose now, got ({}, {}, {})",
            now(0), now(1), now(2));
    const double moved = (now.head<2>() - last_update.head<2>()).norm();
    const double turned = std::abs(wrap_angle(now(2) - last_update(2)));
    return moved >= linear_update || turned >= angular_update;
  }
};

}  // namespace implicit::slam
