// Fuzz target: the SLAM data readers of src/slam/dataset.cpp, as `implicit slam` runs them.
//
// An input is five files separated by lines "%%": slam-synthetic/carpark_controls.csv,
// slam-synthetic/landmarks.csv (together: load_carpark_scenario), a reference data set
// (read_reference_csv, with the landmarks just read when they loaded), a reference EKF trace
// (read_reference_trace) and a robot log with its "# vehicle" line (read_slam_log). Each reader is
// tried on its own file; each must accept it or throw ParseError / InvalidArgument. Anything else
// (another exception, a crash, a sanitizer report) is a finding.

#include <cstdint>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/slam/dataset.hpp"
#include "scratch.hpp"

namespace {

template <typename Read>
void expect_parse_or_reject(Read&& read) {
  try {
    read();
  } catch (const implicit::ParseError&) {
  } catch (const implicit::InvalidArgument&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace implicit::slam;
  const auto& dir = implicit::fuzz::scratch();
  const auto parts = implicit::fuzz::split_files(implicit::fuzz::as_text(data, size), 5);
  dir.write("slam-synthetic/carpark_controls.csv", parts[0]);
  dir.write("slam-synthetic/landmarks.csv", parts[1]);
  const auto reference = dir.write("reference.csv", parts[2]);
  const auto trace = dir.write("trace.csv", parts[3]);
  const auto log = dir.write("run.log", parts[4]);

  std::vector<Landmark> landmarks;
  expect_parse_or_reject([&] { landmarks = load_carpark_scenario(dir.path()).landmarks; });
  expect_parse_or_reject([&] { read_reference_csv(reference, landmarks); });
  expect_parse_or_reject([&] { read_reference_trace(trace); });
  expect_parse_or_reject([&] { read_slam_log(log); });
  return 0;
}
