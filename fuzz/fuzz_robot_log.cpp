// Fuzz target: the plain-text robot log (src/robot/log_format.cpp) and what a run makes of it.
//
// Properties checked on every input:
//  * the reader accepts it or throws ParseError / InvalidArgument (anything else is a finding:
//    another exception, a crash, a sanitizer report, a hang);
//  * an accepted log round-trips: write_robot_log then parse_robot_log gives the same log, bit for
//    bit (17 significant digits);
//  * the step schedule and truth interpolation of `implicit mcl/slam --data` run on it, and the
//    odometry and truth interpolation of `implicit mcl --sensor laser --data` at its scans; every
//    `laser` record passes LaserScan::validate, and a written log is told from a CARMEN log;
//  * a log of at most kFuzzRunSteps steps goes through the runs themselves, with a few particles:
//    Monte Carlo localization with both proposals and EKF-SLAM on the same steps; each accepts
//    it or refuses it with ParseError / InvalidArgument (a log that reads but cannot be run), never
//    crashes.
// A gzip-compressed input (magic bytes 1f 8b) goes through read_robot_log, as a .gz file would.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "scratch.hpp"

namespace {

using namespace implicit::robot;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "fuzz_robot_log: round trip changed %s\n", what);
  std::abort();
}

template <typename A, typename B>
bool same_vector(const A& a, const B& b) {
  return a.size() == b.size() && (a.array() == b.array()).all();
}

// The records of laser runs: map, laser_mount, odometry, laser (ranges may be +inf).
void require_same_laser_run(const RobotLog& a, const RobotLog& b) {
  if (a.map.has_value() != b.map.has_value() || (a.map && a.map->file != b.map->file))
    fail("`map`");
  if (a.laser_mount.has_value() != b.laser_mount.has_value() ||
      (a.laser_mount &&
       (a.laser_mount->x != b.laser_mount->x || a.laser_mount->y != b.laser_mount->y ||
        a.laser_mount->yaw != b.laser_mount->yaw)))
    fail("`laser_mount`");
  if (a.odometry.size() != b.odometry.size()) fail("the odometry count");
  for (std::size_t k = 0; k < a.odometry.size(); ++k)
    if (a.odometry[k].time != b.odometry[k].time ||
        !same_vector(a.odometry[k].pose, b.odometry[k].pose))
      fail("an odometry record");
  if (a.laser_scans.size() != b.laser_scans.size()) fail("the laser count");
  for (std::size_t k = 0; k < a.laser_scans.size(); ++k) {
    const LaserScan &sa = a.laser_scans[k], &sb = b.laser_scans[k];
    if (sa.time != sb.time || sa.angle_min != sb.angle_min ||
        sa.angle_increment != sb.angle_increment || sa.range_min != sb.range_min ||
        sa.range_max != sb.range_max || sa.ranges != sb.ranges)
      fail("a laser record");
  }
}

void require_same(const RobotLog& a, const RobotLog& b) {
  if (a.landmarks.size() != b.landmarks.size()) fail("the landmark count");
  for (std::size_t k = 0; k < a.landmarks.size(); ++k)
    if (a.landmarks.id(k) != b.landmarks.id(k) ||
        !same_vector(a.landmarks.position(k), b.landmarks.position(k)))
      fail("a landmark");
  if (a.initial.has_value() != b.initial.has_value()) fail("the presence of `initial`");
  if (a.initial &&
      (a.initial->time != b.initial->time || !same_vector(a.initial->mean, b.initial->mean) ||
       !same_vector(a.initial->std, b.initial->std)))
    fail("`initial`");
  if (a.controls.size() != b.controls.size()) fail("the control count");
  for (std::size_t k = 0; k < a.controls.size(); ++k)
    if (a.controls[k].time != b.controls[k].time || !same_vector(a.controls[k].u, b.controls[k].u))
      fail("a control");
  if (a.scans.size() != b.scans.size()) fail("the scan count");
  for (std::size_t k = 0; k < a.scans.size(); ++k) {
    const auto &sa = a.scans[k], &sb = b.scans[k];
    if (sa.time != sb.time || sa.observations.size() != sb.observations.size()) fail("a scan");
    for (std::size_t j = 0; j < sa.observations.size(); ++j)
      if (sa.observations[j].landmark_id != sb.observations[j].landmark_id ||
          !same_vector(sa.observations[j].z, sb.observations[j].z))
        fail("an observation");
  }
  require_same_laser_run(a, b);
  if (a.truth.size() != b.truth.size()) fail("the truth count");
  for (std::size_t k = 0; k < a.truth.size(); ++k)
    if (a.truth[k].time != b.truth[k].time ||
        !same_vector(a.truth[k].position, b.truth[k].position) ||
        a.truth[k].heading != b.truth[k].heading)
      fail("a truth record");
}

// Longer logs are read and scheduled above, but not run: a fuzz input should take milliseconds.
constexpr std::size_t kFuzzRunSteps = 200;

template <typename Run>
void run_or_refuse(Run&& run) {
  try {
    run();
  } catch (const implicit::ParseError&) {  // e.g. no `initial` record: not a runnable log
  } catch (const implicit::InvalidArgument&) {
  }
}

// What `implicit mcl --data` and `implicit slam --data` run on an accepted log, briefly.
void run_briefly(const RobotLog& log, std::size_t steps) {
  if (steps == 0 || steps > kFuzzRunSteps) return;
  const UteParams vehicle;  // the Car Park's Ute, as a log without a `vehicle` record runs
  run_or_refuse([&] {
    const implicit::filter::LocalizationProblem problem =
        implicit::filter::make_problem(log, vehicle.dt);
    implicit::filter::FilterOptions options;
    options.particles = 4;
    const UteModel model(vehicle);
    const RangeBearingSensor sensor;
    implicit::filter::run_localization(problem, model, sensor,
                                       implicit::filter::BootstrapProposal{}, options);
    implicit::filter::run_localization(problem, model, sensor, implicit::filter::ImplicitProposal{},
                                       options);
  });
  run_or_refuse([&] {
    const implicit::slam::SlamDataset data =
        implicit::slam::dataset_from_robot_log(log, vehicle, "input.log");
    implicit::slam::SlamOptions options;
    options.method = implicit::slam::SlamMethod::kEkf;
    implicit::slam::run_filter(data, options);
  });
}

RobotLog read(std::string_view text) {
  if (text.size() >= 2 && static_cast<unsigned char>(text[0]) == 0x1f &&
      static_cast<unsigned char>(text[1]) == 0x8b)
    return read_robot_log(implicit::fuzz::scratch().write("input.log.gz", text));
  std::istringstream in{std::string(text)};
  return parse_robot_log(in, "input.log");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  RobotLog log;
  try {
    log = read(implicit::fuzz::as_text(data, size));
  } catch (const implicit::ParseError&) {
    return 0;
  } catch (const implicit::InvalidArgument&) {
    return 0;
  }
  std::ostringstream out;
  write_robot_log(out, log);
  std::istringstream back(out.str());
  require_same(log, parse_robot_log(back, "written.log"));

  // What `implicit mcl --data` does next: steps from the initial time, scans within half a step.
  const double start = log.initial ? log.initial->time : 0.0;
  const StepSchedule schedule = make_schedule(log, start, 0.0125);
  interpolate_truth(log, schedule);
  // What `implicit mcl --sensor laser --data` does with it: odometry and truth at the scans.
  std::vector<double> times;
  for (const LaserScan& scan : log.laser_scans) {
    scan.validate("fuzz");  // the reader's checks imply LaserScan's
    times.push_back(scan.time);
  }
  interpolate_odometry(log, times);
  interpolate_truth(log, times);
  if (!log.laser_scans.empty() && !is_robot_log(out.str())) fail("the format detection");
  run_briefly(log, schedule.steps.size());
  return 0;
}
