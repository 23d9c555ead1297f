// Fuzz target: the CARMEN log reader (src/robot/carmen.cpp).
//
// Properties checked on every input:
//  * the reader accepts it or throws ParseError / InvalidArgument (anything else is a finding:
//    another exception, a crash, a sanitizer report, a hang);
//  * an accepted log is consistent: one laser pose, odometry pose, line and rear flag per scan,
//    scan lines increasing within the file, every scan valid (LaserScan::validate) with finite,
//    non-negative ranges and finite poses;
//  * keeping the rear laser only adds scans, and a fixed range_max is applied to every scan.
// A gzip-compressed input (magic bytes 1f 8b) goes through read_carmen, as a .gz file would.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "implicit/core/error.hpp"
#include "implicit/robot/carmen.hpp"
#include "scratch.hpp"

namespace {

using namespace implicit::robot;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "fuzz_carmen_log: %s\n", what);
  std::abort();
}

void require_consistent(const CarmenLog& log) {
  const std::size_t n = log.scans.size();
  if (n == 0) fail("a log without scans was accepted");
  if (log.laser_poses.size() != n || log.odometry_poses.size() != n || log.scan_lines.size() != n ||
      log.rear.size() != n)
    fail("the per-scan vectors differ in length");
  if (log.skipped_lines > log.lines) fail("more lines skipped than read");
  for (std::size_t k = 0; k < n; ++k) {
    if (log.scan_lines[k] == 0 || log.scan_lines[k] > log.lines ||
        (k > 0 && log.scan_lines[k] <= log.scan_lines[k - 1]))
      fail("a scan's line is out of order or out of the file");
    if (!log.laser_poses[k].allFinite() || !log.odometry_poses[k].allFinite())
      fail("a non-finite pose was accepted");
    const LaserScan& s = log.scans[k];
    s.validate("fuzz_carmen_log");  // throws InvalidArgument: a finding here (not caught)
    if (!std::isfinite(s.time)) fail("a non-finite time was accepted");
    for (double r : s.ranges)
      if (!std::isfinite(r) || r < 0) fail("a non-finite or negative range was accepted");
  }
  for (const CarmenLog::Odometry& o : log.odometry)
    if (!o.pose.allFinite() || !std::isfinite(o.time) || !std::isfinite(o.tv) ||
        !std::isfinite(o.rv))
      fail("a non-finite ODOM field was accepted");
}

CarmenLog read(std::string_view text, const CarmenOptions& options) {
  if (text.size() >= 2 && static_cast<unsigned char>(text[0]) == 0x1f &&
      static_cast<unsigned char>(text[1]) == 0x8b)
    return read_carmen(implicit::fuzz::scratch().write("input.log.gz", text), options);
  return parse_carmen(text, "input.log", options);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text = implicit::fuzz::as_text(data, size);
  CarmenLog log;
  try {
    log = read(text, {});
  } catch (const implicit::ParseError&) {
    return 0;
  } catch (const implicit::InvalidArgument&) {
    return 0;
  }
  require_consistent(log);

  // The rear laser's lines are skipped unread above: they may still be malformed.
  try {
    const CarmenLog both = read(text, {.rear_laser = true});
    require_consistent(both);
    if (both.scans.size() < log.scans.size()) fail("keeping the rear laser lost scans");
  } catch (const implicit::ParseError&) {
  }
  const CarmenLog fixed = read(text, {.range_max = 7.5});
  for (const LaserScan& s : fixed.scans)
    if (s.range_max != 7.5) fail("the range_max option was not applied");
  return 0;
}
