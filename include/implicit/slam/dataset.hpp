#pragma once
// SLAM data sets: controls, range-bearing observations, and (optionally) the truth.
//
// Step convention (spec §3.6 and the reference files): row 0 is the initial pose; step n = 1..N
// applies control u_n to move from pose n-1 to pose n, then processes the observations of step n.
//
//   auto scenario = slam::load_carpark_scenario(slam::default_data_dir());
//   slam::SyntheticConfig cfg;                     // paper-like truth, laser every step
//   slam::SlamDataset data = slam::generate_synthetic(scenario, cfg, /*seed=*/1);
//   for (std::size_t n = 1; n <= data.steps(); ++n) { data.control(n); data.observations(n); }
//
// Mistakes to avoid: using the encoder speed as vc (the files hold the axle speed already), and
// reading the bearing with 0 = straight ahead (here pi/2 = ahead, 0 = right, as the SICK laser).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "implicit/robot/log_format.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::slam {

using robot::Control;
using robot::Landmark;
using robot::Measurement;
using robot::Pose;

/// One range-bearing detection. `landmark` is the true landmark id (>= 0) when known, else -1.
struct Observation {
  Measurement z = Measurement::Zero();
  int landmark = -1;
};

struct SlamDataset {
  std::string name;
  robot::UteParams vehicle;   ///< geometry and dt (noise settings belong to the filter)
  std::string vehicle_model;  ///< the model a log declares ("ute", ...); "" if none
  /// The `vehicle` record's key=value pairs as declared (a model other than the Ute builds from
  /// them); empty if the log declares none.
  std::vector<std::pair<std::string, double>> vehicle_parameters;
  /// read_slam_log: the log declares no vehicle, neither by record nor by `# vehicle` comment, so
  /// the Car Park's Ute was assumed (the CLI says so on stderr and in its JSON).
  bool vehicle_assumed = false;
  std::vector<double> step_dt;            ///< step_dt[n-1] = length of step n [s]; empty: dt
  Pose initial_pose = Pose::Zero();       ///< known initial pose (row 0)
  std::vector<Control> controls;          ///< controls[n-1] = u_n, n = 1..N
  std::vector<Observation> detections;    ///< all detections, step by step
  std::vector<std::size_t> offsets;       ///< detections of step n: [offsets[n-1], offsets[n])
  std::vector<Pose> truth;                ///< N+1 true poses (row 0 = initial) or empty
  std::vector<std::uint8_t> truth_valid;  ///< per row: 1 when truth[n] is known (empty = all)
  bool truth_has_heading = true;          ///< false when the truth is a position fix (GPS)
  std::vector<Landmark> landmarks;        ///< true map (may be empty)
  /// read_slam_log: scans the step schedule left out (farther than half a step from every
  /// control, or a second scan on one control), and the detections in them.
  int scans_unscheduled = 0, detections_unscheduled = 0;

  std::size_t steps() const { return controls.size(); }
  const Control& control(std::size_t n) const { return controls[n - 1]; }
  std::span<const Observation> observations(std::size_t n) const {
    return {detections.data() + offsets[n - 1], offsets[n] - offsets[n - 1]};
  }
  bool has_truth(std::size_t n) const {
    return !truth.empty() && (truth_valid.empty() || truth_valid[n] != 0);
  }
  std::size_t observation_count() const { return detections.size(); }
  double step_length(std::size_t n) const { return step_dt.empty() ? vehicle.dt : step_dt[n - 1]; }

  /// Checks sizes, finiteness and ranges; throws InvalidArgument naming the step and field.
  void validate() const;
};

/// Builds a data set step by step (keeps offsets consistent).
class SlamDatasetBuilder {
 public:
  explicit SlamDatasetBuilder(SlamDataset& d) : d_(d) {
    d_.offsets.assign(1, 0);
    d_.controls.clear();
    d_.detections.clear();
  }
  /// Starts step n = steps()+1 with control u.
  void begin_step(const Control& u) {
    d_.controls.push_back(u);
    d_.offsets.push_back(d_.detections.size());
  }
  void add_observation(const Observation& o) {
    d_.detections.push_back(o);
    ++d_.offsets.back();
  }

 private:
  SlamDataset& d_;
};

/// The Car Park scenario of spec §3.6: recorded controls, surveyed beacons, initial pose.
struct SlamScenario {
  std::string name = "carpark";
  robot::UteParams vehicle;
  Pose initial_pose{4.734, 4.138, 4.098};
  std::vector<Control> controls;    ///< u_1..u_N (axle speed, steering)
  std::vector<Landmark> landmarks;  ///< true landmarks, id = index
};

enum class TruthMode {
  kPaper,       ///< noise-free integration of the controls (smooth path): reproduces the tables
  kConsistent,  ///< truth sampled from the motion model with the filter's own Sigma1 (for NEES)
};

struct SyntheticConfig {
  TruthMode truth = TruthMode::kPaper;
  int laser_every = 1;               ///< a laser observation at steps n with n % laser_every == 0
  double max_range = 15.0;           ///< visible: range <= max_range and bearing in [0, pi]
  double min_range = 0.0;            ///< visible also needs range >= min_range
  robot::UteParams motion;           ///< process noise used to sample the consistent truth
  robot::RangeBearingSensor sensor;  ///< Sigma2 of the simulated laser
};

/// Synthetic data set (spec §3.6): one uniformly chosen visible landmark per laser step,
/// z = h(x_true, m) + v (dropped in the rare case that the noisy range is <= 0). Randomness:
/// Rng({seed, n, 0, kData}) for the sensor at step n and Rng({seed, n, 1, kData}) for the
/// consistent-mode process noise.
SlamDataset generate_synthetic(const SlamScenario& scenario, const SyntheticConfig& config,
                               std::uint64_t seed);

/// Noise-free integration of the controls from the initial pose (N+1 poses).
std::vector<Pose> integrate_controls(const robot::UteModel& model, const Pose& x0,
                                     std::span<const Control> controls);

/// A denser landmark field for scaling studies: the Car Park controls repeated `laps` times
/// (a longer route) and `landmarks` landmarks placed 3-12 m either side of the noise-free path,
/// spread evenly along it. Deterministic in `seed`.
SlamScenario make_dense_scenario(const SlamScenario& base, int laps, int landmarks,
                                 std::uint64_t seed);

/// The bundled data folder: $IMPLICIT_DATA_DIR when set, else ../share/implicit/data next to the
/// running executable (an install, or the build tree's link to data/ of the source tree;
/// core/share_dir.hpp).
/// Throws InvalidArgument naming the places looked when there is none.
std::filesystem::path default_data_dir();

/// Reads data/slam-synthetic/{carpark_controls.csv, landmarks.csv} into the Car Park scenario.
SlamScenario load_carpark_scenario(const std::filesystem::path& data_dir);

/// Reads one reference file (CSV, optionally gzip) with the columns
/// n,t_s,vc,alpha,x_true,y_true,beta_true,has_obs,z_r,z_b,landmark (see its README).
SlamDataset read_reference_csv(const std::filesystem::path& path,
                               const std::vector<Landmark>& landmarks);

/// Reads a reference EKF trace (n,x_hat,y_hat,beta_hat), returning N+1 poses.
std::vector<Pose> read_reference_trace(const std::filesystem::path& path);

/// A data set from a plain-text robot log (implicit/robot/log_format.hpp): every control at or
/// after the `initial` time is one step, scans attach to the nearest step (within dt/2), truth is
/// interpolated to the step times, landmark ids become indices in record order.
SlamDataset dataset_from_robot_log(const robot::RobotLog& log, const robot::UteParams& vehicle,
                                   const std::string& name);
/// The same for any robot: only its nominal step dt [s] is needed here (the filter brings the
/// motion model, SlamOptions::model).
SlamDataset dataset_from_robot_log(const robot::RobotLog& log, double dt, const std::string& name);

/// Reads a robot log (plain or gzip). The vehicle comes from its `vehicle` record (docs/formats.md;
/// for another model than the Ute, `vehicle.dt` holds its declared dt; a key the model does not
/// have is an InvalidArgument naming the file); logs without one may carry the older comment line
/// "# vehicle dt=0.025 L=2.83 H=0.76 a=0.95 b=0.5" (Car Park values when absent too, and
/// `vehicle_assumed` set).
SlamDataset read_slam_log(const std::filesystem::path& path);

/// Writes a data set as a robot log with its `vehicle` record (steps at the times step_dt gives,
/// else step n at time n dt; gzip when the name ends in .gz).
void write_slam_log(const SlamDataset& d, const std::filesystem::path& path);

/// All lines of a text file, transparently gunzipped when it is gzip-compressed. Throws
/// ParseError naming the file when it cannot be read.
std::vector<std::string> read_text_lines(const std::filesystem::path& path);

}  // namespace implicit::slam
