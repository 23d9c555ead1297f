#pragma once
// A reader for CARMEN robot logs (text, one message per line; plain or gzip-compressed), the
// format of the classic indoor laser data sets (data/carmen/README.md).
//
//   robot::CarmenLog log = robot::read_carmen("data/carmen/intel-corrected.log.gz");
//   const LaserScan& scan = log.scans[k];     // 180 beams from -90 deg, 1 deg apart
//   Pose where = log.laser_poses[k];          // the laser's pose recorded with it (world frame)
//
// Messages read (fields separated by blanks; ipc_hostname is any word):
//   FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname
//       logger_timestamp                                          (old format; RLASER alike)
//   ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
//       remission_mode n r_1 ... r_n m rem_1 ... rem_m laser_x laser_y laser_theta robot_x
//       robot_y robot_theta tv rv forward_safety_dist side_safety_dist turn_axis ipc_timestamp
//       ipc_hostname logger_timestamp                             (new format; ROBOTLASER2 alike)
//   ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
// Every field is required, so that a line with a wrong count n is caught by its length; the
// ipc_hostname is any word, the rest are numbers. A scan's time is its ipc_timestamp. Lines
// starting with '#' are comments. Other messages (PARAM, SYNC, NEFF, TRUEPOS, RAWLASER1, ...) are
// skipped and counted; a message name must still look like one (upper-case letters, digits, '_'),
// so that a file of another kind is refused, not skipped.
//
// Beam angles of the old format. FLASER lines do not say where the beams point. CARMEN's own
// reader (carmen_laser_guess_angle_increment) and GMapping's assume a SICK LMS scanning from the
// right (-90 deg) counter-clockwise: beam i at -pi/2 + i * increment, with
//   increment = pi/180 (1 deg) for 180 and 181 beams, pi/360 (0.5 deg) for 360 and 361 beams,
//   pi/(n - 1) for any other n >= 2 (n beams over 180 deg, both ends included), pi for n = 1.
// So 180 beams span -90 to +89 deg and 181 span -90 to +90 deg (the 180-beam logs lack the
// leftmost beam; they are not centred). ROBOTLASER1 gives start_angle and angular_resolution.
//
// "No return". A SICK reports a reading at its maximum when nothing reflects; it is not a wall
// (LaserScan: readings >= range_max are no return). ROBOTLASER1 states maximum_range, used as
// range_max. For the old format (CarmenOptions::range_max = 0, automatic), with m the largest
// reading of the log's kept FLASER/RLASER scans:
//   m >= 80 m:       range_max = 80 m: readings >= 80 m are no return (the 81.83 and 81.91 of
//                    the Intel and Freiburg 079 logs; a SICK in its 80 m mode measures < 80 m);
//   50 <= m < 80 m:  range_max = m: readings equal to the log's maximum are no return (ACES: 50);
//   m < 50 m:        range_max = 80 m (CARMEN's default maximum_range for old messages): no
//                    reading is taken for no return.
// A positive CarmenOptions::range_max overrides this for every scan, ROBOTLASER1 too.
// range_min is 0.
//
// Refused with a ParseError "file:line: MESSAGE field 'name': expected ..., got ...": a line
// with fewer or more fields than its n (and m) promise; a field that is not a
// number; n <= 0 or n > 100000 (m < 0 or m > 100000); a non-finite number (NaN, inf) anywhere;
// a negative range; a ROBOTLASER1 with a zero angular_resolution or a maximum_range <= 0; a log
// with no laser scan at all. Each scan then passes LaserScan::validate("file:line").

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

struct CarmenOptions {
  bool rear_laser = false;  ///< also keep RLASER and ROBOTLASER2 scans (else skipped, counted)
  double range_max = 0.0;   ///< [m] readings at or above it are no return; 0: automatic (above)

  void validate() const;
};

struct CarmenLog {
  std::string source;                   ///< the file name given, for messages
  std::vector<LaserScan> scans;         ///< in file order
  std::vector<Pose> laser_poses;        ///< pose recorded with each scan (world frame, the laser's)
  std::vector<Pose> odometry_poses;     ///< the robot's odometry pose recorded with each scan
  std::vector<std::size_t> scan_lines;  ///< line of each scan in the file (1-based)
  std::vector<bool> rear;               ///< scan k came from the rear laser (rear_laser option)

  struct Odometry {
    double time = 0.0;  ///< ipc_timestamp [s]
    Pose pose = Pose::Zero();
    double tv = 0.0, rv = 0.0;  ///< translational [m/s] and rotational [rad/s] speeds
  };
  std::vector<Odometry> odometry;  ///< ODOM messages

  std::size_t lines = 0;  ///< lines in the file
  std::size_t skipped_lines =
      0;  ///< message lines not read: other messages, rear laser unless kept
};

/// Beam spacing [rad] of an old-format (FLASER/RLASER) scan of n beams; beam i points at
/// -pi/2 + i * carmen_angle_increment(n). See the header comment.
double carmen_angle_increment(std::size_t beams);

/// Parses CARMEN log text; `name` (a file name) is used in messages only.
CarmenLog parse_carmen(std::string_view text, std::string_view name,
                       const CarmenOptions& options = {});

/// Reads a CARMEN log file, plain or gzip-compressed (detected from its first bytes, any name).
CarmenLog read_carmen(const std::filesystem::path& file, const CarmenOptions& options = {});

}  // namespace implicit::robot
