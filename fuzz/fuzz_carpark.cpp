// Fuzz target: the Car Park CSV readers (src/robot/carpark.cpp, src/robot/csv_table.cpp) and the
// conversion to a robot log, as `implicit mcl` runs them.
//
// An input is the five files of data/carpark, in this order, separated by lines "%%":
// carpark_dr.csv, carpark_gps.csv, carpark_beacons.csv, carpark_laser_range_cm.csv,
// carpark_laser_intensity.csv. A file that starts with the gzip magic bytes is read as gzip.
// The readers must accept the folder or throw ParseError / InvalidArgument; anything else (another
// exception, a crash, a sanitizer report) is a finding.

#include <cstdint>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/carpark.hpp"
#include "scratch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace implicit::robot;
  static const char* const kFiles[] = {"carpark_dr.csv", "carpark_gps.csv", "carpark_beacons.csv",
                                       "carpark_laser_range_cm.csv", "carpark_laser_intensity.csv"};
  const auto& dir = implicit::fuzz::scratch();
  const auto parts = implicit::fuzz::split_files(implicit::fuzz::as_text(data, size), 5);
  for (std::size_t k = 0; k < parts.size(); ++k) dir.write(kFiles[k], parts[k]);
  try {
    const CarParkData car = load_carpark(dir.path());
    const UteModel model;
    const RobotLog log = carpark_to_log(car, model);
    const StepSchedule schedule = make_schedule(log, log.initial->time, 0.5 * 0.025);
    const auto poses = dead_reckoning(model, log.initial->mean, schedule);
    detection_residuals(log, schedule, poses);
    interpolate_truth(log, schedule);
  } catch (const implicit::ParseError&) {
  } catch (const implicit::InvalidArgument&) {
  }
  return 0;
}
