#pragma once
// The plain-text robot log: what a localization (or SLAM) run consumes, for any dataset.
//
// One record per line, fields separated by spaces or tabs, '#' starts a comment. Times in seconds,
// lengths in metres, angles in radians. Full description: docs/formats.md, "Plain-text log format".
//
//   # implicit robot log v1
//   vehicle ute dt=0.025 L=2.83 H=0.76 a=3.78 b=0.5   # the robot the controls drive (optional)
//   landmark 1 2.8953 -4.0353                 # id east north (known map / ground-truth map)
//   initial 45.047 4.734 4.138 4.098 0.1 0.1 0.02   # t x y heading, then std devs of the prior
//   control 45.049 2.0435 0.2764              # t u1 u2: the motion model's control for the
//                                             # step that ends at t (Ute: axle speed vc, steering)
//   scan 45.103 2                             # t n: an observation set with n observations,
//   obs 7.301 1.2312                          #   then n lines: range bearing [landmark id]
//   obs 12.05 2.0100 4
//   truth 45.047 5.1048 4.2044 [heading]      # t x y [heading]: ground truth (GPS, simulation)
//
// Laser runs (`implicit mcl --sensor laser --data`) read four more records:
//
//   map lab.yaml                              # the map_server YAML the scans are matched against
//                                             # (relative to the log's folder), at most one
//   laser_mount 0.2 0 0                       # x y theta: the laser on the robot (default 0 0 0)
//   odometry 12.5 3.02 -1.4 0.31              # t x y theta: the robot's odometry pose at t
//   laser 12.5 -1.5708 0.0174533 0.05 30 3 2.1 inf 1.87
//                                             # t angle_min angle_increment range_min range_max
//                                             # n r_1 ... r_n ('inf': no return), LaserScan's
//
// Records of one kind must have strictly increasing times (scans and truth too); the kinds may
// be interleaved in any order. A landmark id used by an `obs` line must be defined by a `landmark`
// line (anywhere in the file). A `map` file must exist (read_robot_log checks it; a log parsed
// from a stream is not checked, as it has no folder). Readers reject malformed input with a
// ParseError naming the file, the line and the field ("log.txt:12: field 'bearing': expected a
// finite number, got 'nan'").
//
//   RobotLog log = read_robot_log("run.log");   // or "run.log.gz": gzip is read transparently
//   write_robot_log("copy.log", log);        // round-trips exactly (17 significant digits)

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::robot {

struct Observation {
  Measurement z;         ///< (range [m], bearing [rad])
  int landmark_id = -1;  ///< known id (labelled data), or -1 (unlabelled: associate)
};

struct TimedControl {
  double time = 0.0;  ///< end of the step this control drives
  Control u;
};

struct ObservationSet {
  double time = 0.0;
  std::vector<Observation> observations;  ///< may be empty (a scan that saw nothing)
};

struct TruthRecord {
  double time = 0.0;
  Vec<2> position;
  std::optional<double> heading;  ///< absent when the source has no heading (e.g. GPS at rest)
};

struct PosePrior {
  double time = 0.0;
  Pose mean;
  Vec<3> std;            ///< standard deviations of x, y, heading
  std::size_t line = 0;  ///< line of the 'initial' record in its file (0: not read from one)
};

/// The `vehicle` record: which motion model the controls are for, and its geometry.
struct VehicleDeclaration {
  std::string model;  ///< e.g. "ute" (u = axle speed, steering) or "unicycle" (u = v, omega)
  std::vector<std::pair<std::string, double>> parameters;  ///< key=value, in file order

  /// The value of `key`, if declared.
  std::optional<double> parameter(const std::string& key) const {
    for (const auto& [k, v] : parameters)
      if (k == key) return v;
    return std::nullopt;
  }
};

/// The physically sensible range of a vehicle parameter, the same for the `vehicle` record and
/// the older `# vehicle` comment: dt in (0, 60] s, L in (0, 100] m, H, a, b in [-100, 100] m.
/// An empty string when `value` lies in it (or `key` is none of these), otherwise what was
/// expected, e.g. "a time step in (0, 60] s", for the reader's message, which adds the key, the
/// value and the line. Without it a=1e300 or dt=100 ran and turned every metric into NaN or
/// dropped every observation, silently.
std::string vehicle_parameter_out_of_range(std::string_view key, double value);

/// The declarations of the shipped models: "ute" (dt, L, H, a, b) and "unicycle" (dt).
VehicleDeclaration declare_vehicle(const UteParams& p);
VehicleDeclaration declare_vehicle(const UnicycleParams& p);
/// `base` with the declared parameters (keys as declare_vehicle writes them); a key the model
/// does not have is an InvalidArgument naming it and the keys it has.
UteParams ute_params(const VehicleDeclaration& v, UteParams base = {});
UnicycleParams unicycle_params(const VehicleDeclaration& v, UnicycleParams base = {});

/// The `map` record: the occupancy map a laser run matches its scans against.
struct MapReference {
  std::string file;      ///< as written: a path without blanks, relative to the log's folder
  std::size_t line = 0;  ///< line of the record in its file (0: not read from one)
};

/// The `odometry` record: the robot's pose as its odometry reports it (its own frame) at `time`.
struct OdometryRecord {
  double time = 0.0;
  Pose pose;
};

struct RobotLog {
  std::optional<VehicleDeclaration> vehicle;  ///< absent in logs that do not declare one
  LandmarkMap landmarks;
  std::optional<PosePrior> initial;
  std::vector<TimedControl> controls;
  std::vector<ObservationSet> scans;
  std::vector<TruthRecord> truth;
  std::optional<MapReference> map;        ///< laser runs: the map file
  std::optional<LaserMount> laser_mount;  ///< absent: the laser sits at the robot's origin
  std::vector<OdometryRecord> odometry;   ///< laser runs: the control (increments)
  std::vector<LaserScan> laser_scans;     ///< `laser` records, in time order
  std::string source;  ///< the file (or stream name) it was parsed from, for error messages
};

/// The file of the log's `map` record: as written when absolute, else relative to the folder of
/// log.source. Empty without a `map` record.
std::filesystem::path map_file(const RobotLog& log);

/// Whether `text` is a robot log: its first record (the first line that is not blank or a
/// comment) starts with one of the record kinds above. The other text logs the tools read,
/// CARMEN's, start with an upper-case message name (FLASER, ODOM, PARAM, ...), never one of them.
bool is_robot_log(std::string_view text);

/// Parses a log from a stream; `name` is used in error messages.
RobotLog parse_robot_log(std::istream& in, const std::string& name);
/// Reads a log file (plain or gzip); its `map` record must name an existing file.
RobotLog read_robot_log(const std::filesystem::path& path);
/// A `map` record whose file has a blank, '#' or a line break is an InvalidArgument: it would
/// not read back.
void write_robot_log(std::ostream& out, const RobotLog& log);
/// Writes the log to a file, gzip-compressed when the name ends in ".gz".
void write_robot_log(const std::filesystem::path& path, const RobotLog& log);

// ---- From a log to filter steps ------------------------------------------------------------

/// One motion step of a filter: the control, and the observation set applied after it (if any).
struct FilterStep {
  double time = 0.0;
  Control u;
  int scan = -1;  ///< index into RobotLog::scans, or -1 (prediction only)
};

struct StepSchedule {
  std::vector<FilterStep> steps;
  int scans_used = 0;               ///< scans attached to a step
  int scans_with_observations = 0;  ///< attached scans with at least one observation
  int scans_skipped = 0;            ///< scans farther than max_offset from every step, or second
                                    ///< on a step
  int observations_skipped = 0;     ///< observations in the skipped scans
  int observations_used = 0;        ///< observations in the attached scans
};

/// The steps of a run: every control with time >= start_time (minus a 1e-9 s tolerance) is one
/// step; each scan is attached to the step nearest in time if that is within max_offset seconds
/// (use half the step length), otherwise skipped. Two scans on one step: the later one is skipped.
StepSchedule make_schedule(const RobotLog& log, double start_time, double max_offset);

/// What every run on a log needs: an 'initial' record and at least one control at or after its
/// time (a run with no step would score nothing). Throws ParseError naming the source and line.
void require_runnable(const RobotLog& log);
/// The length of each step [s]: from the previous control's time (the first step: the control
/// before it in the log, else the initial time) to its own. Lengths within 1e-9 s of
/// `nominal_dt` are exactly nominal_dt (time stamps are printed with finite precision), and a
/// first step with nothing before it gets nominal_dt.
std::vector<double> step_lengths(const RobotLog& log, const StepSchedule& schedule,
                                 double nominal_dt);

/// Ground truth at each step time, interpolated linearly between truth records; NaN outside
/// their time range and inside gaps longer than max_gap seconds (a straight line across a GPS
/// outage is not where the vehicle was: Victoria Park has 41 outages over 5 s, up to 58 s).
/// Heading is interpolated along the shorter arc and is NaN where either neighbour has none.
struct TruthTrack {
  std::vector<Vec<2>> position;
  std::vector<double> heading;
};
inline constexpr double kDefaultTruthMaxGap = 1.0;  ///< [s]; five periods of a 5 Hz GPS
TruthTrack interpolate_truth(const RobotLog& log, const StepSchedule& schedule,
                             double max_gap = kDefaultTruthMaxGap);
/// The same at arbitrary increasing times (e.g. those of the laser scans).
TruthTrack interpolate_truth(const RobotLog& log, const std::vector<double>& times,
                             double max_gap = kDefaultTruthMaxGap);
/// The odometry pose at each time, interpolated linearly between `odometry` records (heading
/// along the shorter arc, so continuous in the odometry's own frame); NaN outside their time
/// range. No gap limit: odometry has no outages, only a rate.
std::vector<Pose> interpolate_odometry(const RobotLog& log, const std::vector<double>& times);

}  // namespace implicit::robot
