#pragma once
// Synthetic robot logs from any motion model and sensor: truth sampled from the model itself,
// surveyed landmarks, controls at irregular times, range-bearing detections labelled with ids.
//
//   robot::UnicycleModel model;
//   robot::RangeBearingSensor sensor;
//   robot::RobotLog log = robot::simulate_robot_log(model, sensor, robot::square_route_driver(
//                                                   1.0, 1.0, true), {}, /*seed=*/3);
//   log.vehicle = robot::VehicleDeclaration{"unicycle", {{"dt", model.dt()}}};
//   robot::write_robot_log("u.log.gz", log);
//
// The route: a driver function turns the true pose into the next control (a controller that
// follows the corners of a square), so the robot stays inside the landmark field for any seed.
// Randomness: Rng({seed, step, 0, kData}) for the motion noise, ({seed, step, 1, kData}) for the
// sensor, ({seed, 0, 2, kData}) for the step lengths, landmarks and the initial pose.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::robot {

struct SimulationOptions {
  int steps = 1200;       ///< motion steps (controls)
  double min_step = 0.5;  ///< step lengths uniform in [min_step, max_step] x dt()
  double max_step = 1.5;
  int scan_every = 3;          ///< a scan at every k-th control time
  int landmarks = 40;          ///< surveyed landmarks, uniform over the field
  double field_margin = 12.0;  ///< [m] the field extends this far around the route's square
  double route_side = 40.0;    ///< [m] side of the square the driver follows
  double max_range = 15.0;     ///< [m] detections up to this range
  double bearing_min = 0.0;    ///< field of view in the log's bearing convention [rad]
  double bearing_max = kPi;
  Vec<3> initial_std{0.2, 0.2, 0.05};  ///< prior std of the declared initial pose
  int first_landmark_id = 101;         ///< ids first, first + 3, ... (never equal to indices)
};

/// A control law: the control for the next step from the true pose and the step length.
using Driver = std::function<Control(const Pose& pose, double dt)>;

/// Follows the corners of an axis-aligned square [0, side]^2 counter-clockwise. Unicycle controls
/// (v, omega) when `unicycle`, turning on the spot when the heading error exceeds 60 degrees;
/// otherwise Ute controls (axle speed, steering angle within +-0.5 rad).
Driver square_route_driver(double speed, double side, bool unicycle);

/// Simulates a log (see the file comment). The log's `vehicle` is left empty for the caller.
template <VariableStepMotionModel Motion, LandmarkSensor Sensor>
RobotLog simulate_robot_log(const Motion& motion, const Sensor& sensor, const Driver& driver,
                            const SimulationOptions& o, std::uint64_t seed) {
  require(o.steps >= 1 && o.scan_every >= 1 && o.landmarks >= 1,
          "simulate: expected at least one step, scan interval and landmark, got {}, {}, {}",
          o.steps, o.scan_every, o.landmarks);
  require(o.min_step > 0 && o.max_step >= o.min_step,
          "simulate: expected 0 < min_step <= max_step, got {} and {}", o.min_step, o.max_step);
  RobotLog log;
  Rng setup({seed, 0, 2, purpose::kData});
  for (int k = 0; k < o.landmarks; ++k) {
    const double x = -o.field_margin + (o.route_side + 2 * o.field_margin) * setup.uniform();
    const double y = -o.field_margin + (o.route_side + 2 * o.field_margin) * setup.uniform();
    log.landmarks.add(o.first_landmark_id + 3 * k, Landmark(x, y));
  }
  const Pose declared(0.0, 0.0, 0.0);
  Pose x = declared + o.initial_std.cwiseProduct(setup.normal_vector<3>());
  log.initial = PosePrior{0.0, declared, o.initial_std};
  log.truth.push_back({0.0, x.head<2>(), x(2)});
  const Eigen::LLT<Mat2> noise(sensor.noise_covariance());
  double t = 0.0;
  for (int n = 1; n <= o.steps; ++n) {
    const double dt = motion.dt() * (o.min_step + (o.max_step - o.min_step) * setup.uniform());
    const Motion step = motion.with_dt(dt);
    const Control u = driver(x, dt);
    Rng rng({seed, static_cast<std::uint64_t>(n), 0, purpose::kData});
    const Eigen::LLT<Mat3> llt(step.process_covariance(x, u));
    x = step.predict(x, u) + llt.matrixL() * rng.normal_vector<3>();
    t += dt;
    log.controls.push_back({t, u});
    log.truth.push_back({t, x.head<2>(), x(2)});
    if (n % o.scan_every != 0) continue;
    ObservationSet scan;
    scan.time = t;
    Rng sense({seed, static_cast<std::uint64_t>(n), 1, purpose::kData});
    for (std::size_t k = 0; k < log.landmarks.size(); ++k) {
      const Measurement h = sensor.predict(x, log.landmarks.position(k));
      const double bearing = wrap_angle(h(1));
      if (h(0) > o.max_range || bearing < o.bearing_min || bearing > o.bearing_max) continue;
      Measurement z = h + noise.matrixL() * sense.normal_vector<2>();
      z(1) = wrap_angle(z(1));
      if (z(0) <= 0.0) continue;  // a range cannot be negative: the detection is lost
      scan.observations.push_back({z, log.landmarks.id(k)});
    }
    log.scans.push_back(std::move(scan));
  }
  return log;
}

}  // namespace implicit::robot
