// Bad robot logs and data files found by fuzzing and a bad-input table: each is a ParseError
// naming the file and line, never undefined behaviour, a hang or a silent empty run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::robot {
namespace {

RobotLog parse_bad_log(const std::string& text) {
  std::istringstream in(text);
  return parse_robot_log(in, "bad.log");
}

std::string runnable_error(const std::string& text) {
  try {
    require_runnable(parse_bad_log(text));
  } catch (const ParseError& e) {
    return e.what();
  }
  return "no error";
}

// The two-line reproducer: the scan precedes every step, so the nearest-step search starts at
// the first step and must not form an iterator before it.
TEST(LogFormat, ControlsAllBeforeInitialIsAnErrorNamingTheLine) {
  const std::string only_scan = "initial 1 0 0 0 0 0 0\nscan 0.5 0\n";
  EXPECT_EQ(runnable_error(only_scan),
            "bad.log:1: expected 'control' records at or after the 'initial' time 1, got none in "
            "the file");
  const std::string early = "control 0.25 1 0\ncontrol 0.5 1 0\ninitial 1 0 0 0 0 0 0\n";
  EXPECT_EQ(runnable_error(early),
            "bad.log:3: expected 'control' records at or after the 'initial' time 1, got 2 all "
            "earlier (the last at 0.5)");
  EXPECT_EQ(runnable_error("control 0.5 1 0\n"),
            "bad.log: expected an 'initial' record (the prior pose), got none");
  EXPECT_EQ(runnable_error("initial 0 0 0 0 0 0 0\ncontrol 0.5 1 0\n"), "no error");
}

// The `vehicle` record's numbers were only checked to be finite: a=1e300 or dt=100 ran and made
// every metric NaN or dropped every observation. They now have the `# vehicle` comment's ranges.
TEST(LogFormat, VehicleRecordOutsideSensibleRangesIsAnErrorNamingKeyValueAndLine) {
  const std::string body = "initial 0 0 0 0 0 0 0\ncontrol 0.025 1 0\n";
  auto error = [&](const std::string& vehicle) {
    try {
      parse_bad_log(body + vehicle + "\n");
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string ute = "vehicle ute dt=0.025 L=2.83 H=0.76 ";
  EXPECT_EQ(error(ute + "a=1e300 b=0.5"),
            "bad.log:3: field 'a': expected an offset in [-100, 100] m, got '1e300'");
  EXPECT_EQ(error(ute + "a=150 b=0.5"),
            "bad.log:3: field 'a': expected an offset in [-100, 100] m, got '150'");
  EXPECT_EQ(error("vehicle ute L=1e300"),
            "bad.log:3: field 'L': expected a wheelbase in (0, 100] m, got '1e300'");
  EXPECT_EQ(error("vehicle ute dt=100"),
            "bad.log:3: field 'dt': expected a time step in (0, 60] s, got '100'");
  EXPECT_EQ(error("vehicle unicycle dt=0"),
            "bad.log:3: field 'dt': expected a time step in (0, 60] s, got '0'");
  EXPECT_EQ(error("vehicle ute b=-100.5"),
            "bad.log:3: field 'b': expected an offset in [-100, 100] m, got '-100.5'");
  // The bounds themselves are sensible.
  EXPECT_EQ(error("vehicle ute dt=60 L=100 H=-100 a=100 b=0"), "no error");
  EXPECT_EQ(vehicle_parameter_out_of_range("dt", 0.025), "");
  EXPECT_EQ(vehicle_parameter_out_of_range("speed", 1e300), "");  // not a key with a range
}

TEST(LogFormat, ScanBeforeTheFirstStepIsSkipped) {
  const RobotLog log =
      parse_bad_log("initial 0 0 0 0 0 0 0\nscan 0.1 0\ncontrol 1 1 0\nscan 1 0\n");
  const StepSchedule s = make_schedule(log, 0.0, 0.05);
  ASSERT_EQ(s.steps.size(), 1u);
  EXPECT_EQ(s.scans_skipped, 1);  // 0.9 s from the only step
  EXPECT_EQ(s.scans_used, 1);
  EXPECT_EQ(s.steps[0].scan, 1);
  // No step at all: every scan is skipped.
  const StepSchedule none = make_schedule(parse_bad_log("scan 0.5 0\nscan 0.7 0\n"), 1.0, 0.05);
  EXPECT_TRUE(none.steps.empty());
  EXPECT_EQ(none.scans_skipped, 2);
}

TEST(LogFormat, ControlBytesInAFileAreEscapedInTheMessage) {
  std::string message;
  try {
    parse_bad_log(std::string("landmark 1 2\x1b[31m 3\n"));
  } catch (const ParseError& e) {
    message = e.what();
  }
  EXPECT_EQ(message, "bad.log:1: field 'x': expected a finite number, got '2\\x1b[31m'");
  try {
    parse_bad_log("cont\x01rol\x7f 1 2 3\n");
  } catch (const ParseError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("got 'cont\\x01rol\\x7f'"), std::string::npos) << message;
  EXPECT_EQ(printable(std::string(200, 'a'), 10), "aaaaaaaaaa...");
  EXPECT_EQ(printable(std::string("a\0b", 3)), "a\\x00b");
}

TEST(LogFormat, ManyLandmarkIdsAreLookedUpByHash) {
  std::string text;
  for (int id = 0; id < 20000; ++id) text += "landmark " + std::to_string(3 * id + 1) + " 1 2\n";
  const RobotLog log = parse_bad_log(text);
  ASSERT_EQ(log.landmarks.size(), 20000u);
  for (int id : {1, 4, 30001, 59998}) EXPECT_EQ(log.landmarks.index_of(id), (id - 1) / 3) << id;
  for (int id : {0, 2, 59999, 60001}) EXPECT_EQ(log.landmarks.index_of(id), -1) << id;
  EXPECT_THROW(parse_bad_log(text + "landmark 4 0 0\n"), ParseError);
}

TEST(TextInput, AnEndlessFileIsRefusedAtTheSizeBound) {
  std::string message;
  try {
    read_text_file("/dev/zero", std::size_t{1} << 20);
  } catch (const ParseError& e) {
    message = e.what();
  }
  EXPECT_EQ(message.rfind("/dev/zero:1: expected at most 1 MiB of text, got more", 0), 0u)
      << message;
  const auto file = std::filesystem::temp_directory_path() / "implicit_size_bound.txt";
  std::ofstream(file) << "a\nb\nc\n";
  EXPECT_EQ(read_text_file(file, 6), "a\nb\nc\n");
  EXPECT_THROW(read_text_file(file, 5), ParseError);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace implicit::robot
