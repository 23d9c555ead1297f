#pragma once
// The ACFR University Car Park data set (paper §4.1, spec §3.8): reader, beacon extraction from
// the raw laser scans, ground truth, and conversion to the plain-text robot log.
//
//   CarParkData data = load_carpark(default_carpark_dir());     // the bundled data/carpark
//   RobotLog log = carpark_to_log(data, UteModel());            // controls, detections, GPS truth
//   StepSchedule steps = make_schedule(log, log.initial->time, 0.5 * 0.025);
//
// Beacon extraction (spec §3.8): consecutive beams whose intensity is > 0 form one detection; its
// range and bearing are the means over the group; beam k (0-based) has bearing k/2 degrees
// (0 = vehicle's right, 90 degrees = straight ahead). Detections are unlabelled.
// Ground truth: the GPS positions, which sit at the laser (state) point to about 0.1 m, linearly
// interpolated in time. GPS has no heading; the heading reference is the GPS track direction
// minus the slip of the laser point, atan2(a tan(alpha)/L, 1 - b tan(alpha)/L), at fixes where
// the vehicle moves faster than 0.5 m/s (none elsewhere).
//
// Common mistakes: feeding the encoder speed to the model (carpark_to_log converts it to the axle
// speed), and using the mirrored bearing convention (it fits the surveyed beacons twice as badly).

#include <array>
#include <filesystem>
#include <span>
#include <vector>

#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::robot {

inline constexpr int kCarParkBeams = 361;

struct CarParkScan {
  double time = 0.0;
  std::array<double, kCarParkBeams> range{};      ///< [m]; about 81.9 means no return
  std::array<double, kCarParkBeams> intensity{};  ///< 0, or 8192 k for a reflective return
};

struct CarParkData {
  std::vector<double> control_time;   ///< 40 Hz speed/steering records [s]
  std::vector<double> encoder_speed;  ///< rear-left wheel speed [m/s]
  std::vector<double> steering;       ///< steering angle [rad]
  std::vector<double> gps_time;
  std::vector<Vec<2>> gps;  ///< (east, north) [m]
  std::vector<CarParkScan> scans;
  LandmarkMap beacons;  ///< the 15 surveyed beacons, ids 1..15
};

/// The bundled copy: the folder carpark/ of the data folder (see slam::default_data_dir; found
/// through $IMPLICIT_DATA_DIR or the install layout, core/share_dir.hpp). Throws InvalidArgument
/// naming the places looked when there is none.
std::filesystem::path default_carpark_dir();

/// Reads the five CSV files of data/carpark/README.md. Throws ParseError (file, line, field) for a
/// missing file or column, a non-finite value, non-increasing times, or a scan with the wrong
/// number of beams; the range and intensity files must have identical time columns.
CarParkData load_carpark(const std::filesystem::path& dir);

/// Groups consecutive high-intensity beams (spec §3.8) into detections (range, bearing).
std::vector<Measurement> extract_beacon_detections(std::span<const double> range,
                                                   std::span<const double> intensity);

struct CarParkOptions {
  double start_time = 45.047;              ///< t0, the first GPS fix
  Pose initial_pose{4.734, 4.138, 4.098};  ///< fitted initial laser pose at t0 (spec §3.8)
  Vec<3> initial_std{0.1, 0.1, 0.02};      ///< prior std devs (spec §3.9)
  double heading_min_speed = 0.5;          ///< [m/s] below it, GPS gives no heading reference
};

/// The data as a robot log: initial prior, controls (vc axle speed, steering) for every record,
/// every scan with its extracted detections (unlabelled), the 15 beacons, GPS truth positions
/// with the track-derived heading where defined.
RobotLog carpark_to_log(const CarParkData& data, const UteModel& model,
                        const CarParkOptions& options = {});

/// Noise-free integration of the controls from the initial pose: one pose per schedule step.
std::vector<Pose> dead_reckoning(const UteModel& model, const Pose& initial,
                                 const StepSchedule& schedule);

/// A detection placed in the world with a given pose, and its nearest surveyed beacon.
struct DetectionResidual {
  double time = 0.0;
  int scan = 0;  ///< index into RobotLog::scans
  Measurement z;
  Vec<2> world;             ///< detection position in the world frame
  int nearest_beacon = -1;  ///< index into the landmark map
  double distance = 0.0;    ///< [m] to that beacon
};

/// For every scheduled scan, its detections placed with poses[step] (e.g. dead reckoning) and
/// their distance to the nearest beacon: a check of the sensor model and the extraction.
std::vector<DetectionResidual> detection_residuals(const RobotLog& log,
                                                   const StepSchedule& schedule,
                                                   std::span<const Pose> poses);

}  // namespace implicit::robot
