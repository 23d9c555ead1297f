// Fuzz target: the plain-text robot log (src/robot/log_format.cpp) and what a run makes of it.
//
// Properties checked on every input:
//  * the reader accepts it or throws ParseError / InvalidArgument (anything else is a finding:
//    another exception, a crash, a sanitizer report, a hang);
//  * an accepted log round-trips: write_robot_log then parse_robot_log gives the same log, bit for
//    bit (17 significant digits);
//  * the step schedule and truth interpolation of `implicit mcl/slam --data` run on it.
// A gzip-compressed input (magic bytes 1f 8b) goes through read_robot_log, as a .gz file would.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/log_format.hpp"
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
  if (a.truth.size() != b.truth.size()) fail("the truth count");
  for (std::size_t k = 0; k < a.truth.size(); ++k)
    if (a.truth[k].time != b.truth[k].time ||
        !same_vector(a.truth[k].position, b.truth[k].position) ||
        a.truth[k].heading != b.truth[k].heading)
      fail("a truth record");
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
  return 0;
}
