// The plain-text robot log and the Car Park CSV reader: round trip, and the bad-input table
// (every message names the file, the line and the field).
#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/carpark.hpp"
#include "implicit/robot/csv_table.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::robot {
namespace {

const char* kGood = R"(# a small log
landmark 1 2.0 3.0
landmark 7 -1.5 4.25
initial 0.0 0 0 0.5 0.1 0.1 0.02
control 0.025 2.0 0.1   # end-of-line comment
control 0.050 2.0 0.1
scan 0.05 2
obs 3.5 1.2
obs 4.0 1.6 7
scan 0.075 0
truth 0.0 0.1 0.2 0.5
truth 0.05 0.15 0.25
)";

RobotLog parse(const std::string& text) {
  std::istringstream in(text);
  return parse_robot_log(in, "test.log");
}

// Writes `text` gzip-compressed to `path`.
void write_gzip(const std::filesystem::path& path, const std::string& text) {
  gzFile f = gzopen(path.string().c_str(), "wb9");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())),
            static_cast<int>(text.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::filesystem::path scratch_dir(const std::string& tag) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("implicit_" + tag + "_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read_log_error(const std::filesystem::path& path) {
  try {
    read_robot_log(path);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RobotLog, ReadsGzipTransparentlyAndRejectsDamagedGzip) {
  const auto dir = scratch_dir("gzip_log");
  const RobotLog plain = parse(kGood);
  write_gzip(dir / "small.log.gz", kGood);
  const RobotLog zipped = read_robot_log(dir / "small.log.gz");
  std::ostringstream a, b;
  write_robot_log(a, plain);
  write_robot_log(b, zipped);
  EXPECT_EQ(a.str(), b.str());
  // The name without .gz finds the compressed file.
  std::ostringstream c;
  write_robot_log(c, read_robot_log(dir / "small.log"));
  EXPECT_EQ(a.str(), c.str());

  // Truncated: the 8-byte trailer (CRC, length) and some data cut off.
  const std::string bytes = read_bytes(dir / "small.log.gz");
  ASSERT_GT(bytes.size(), 40u);
  write_bytes(dir / "truncated.log.gz", bytes.substr(0, bytes.size() - 20));
  std::string msg = read_log_error(dir / "truncated.log.gz");
  EXPECT_NE(msg.find("truncated.log.gz:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected a complete gzip stream, got corrupt or truncated data"),
            std::string::npos)
      << msg;
  // Corrupt: the compressed body overwritten (header intact, so it is still detected as gzip).
  std::string corrupt = bytes;
  for (std::size_t k = 12; k < corrupt.size() - 8; ++k) corrupt[k] = static_cast<char>(0xA5 ^ k);
  write_bytes(dir / "corrupt.log.gz", corrupt);
  msg = read_log_error(dir / "corrupt.log.gz");
  EXPECT_NE(msg.find("corrupt.log.gz:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected a complete gzip stream"), std::string::npos) << msg;
  std::filesystem::remove_all(dir);
}

TEST(RobotLog, ParsesAndRoundTrips) {
  const RobotLog log = parse(kGood);
  ASSERT_EQ(log.landmarks.size(), 2u);
  EXPECT_EQ(log.landmarks.index_of(7), 1);
  ASSERT_TRUE(log.initial.has_value());
  EXPECT_DOUBLE_EQ(log.initial->mean(2), 0.5);
  ASSERT_EQ(log.controls.size(), 2u);
  ASSERT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(log.scans[0].observations.size(), 2u);
  EXPECT_EQ(log.scans[0].observations[1].landmark_id, 7);
  EXPECT_TRUE(log.scans[1].observations.empty());
  ASSERT_EQ(log.truth.size(), 2u);
  EXPECT_TRUE(log.truth[0].heading.has_value());
  EXPECT_FALSE(log.truth[1].heading.has_value());

  std::ostringstream out;
  write_robot_log(out, log);
  const RobotLog again = parse(out.str());
  std::ostringstream out2;
  write_robot_log(out2, again);
  EXPECT_EQ(out.str(), out2.str());
}

TEST(RobotLog, ScheduleAndTruthInterpolation) {
  const RobotLog log = parse(kGood);
  const StepSchedule s = make_schedule(log, 0.0, 0.0125);
  ASSERT_EQ(s.steps.size(), 2u);
  EXPECT_EQ(s.steps[1].scan, 0);  // scan at 0.05 on the step ending at 0.05
  EXPECT_EQ(s.scans_used, 1);
  EXPECT_EQ(s.scans_skipped, 1);  // 0.075 is 25 ms from the last step
  const TruthTrack t = interpolate_truth(log, s);
  EXPECT_NEAR(t.position[0](0), 0.125, 1e-12);
  EXPECT_TRUE(std::isnan(t.heading[0]));  // one neighbour has no heading
}

// A log whose scans come before every step (here: no control at all) gives a schedule with no
// step and every scan skipped; finding the neighbours of a scan in an empty step list was undefined
// behaviour (fuzz/corpus/robot_log/scan_before_every_control.log replays it under the sanitizers).
TEST(RobotLog, ScheduleOfScansBeforeEveryControl) {
  const RobotLog none = parse("initial 1 0 0 0 0 0 0\nscan 0.5 0\n");
  const StepSchedule s = make_schedule(none, 1.0, 0.0125);
  EXPECT_TRUE(s.steps.empty());
  EXPECT_EQ(s.scans_used, 0);
  EXPECT_EQ(s.scans_skipped, 1);
  const RobotLog early = parse("initial 1 0 0 0 0 0 0\ncontrol 1.025 1 0\nscan 0.5 0\n");
  const StepSchedule e = make_schedule(early, 1.0, 0.0125);
  ASSERT_EQ(e.steps.size(), 1u);
  EXPECT_EQ(e.steps[0].scan, -1);
  EXPECT_EQ(e.scans_skipped, 1);
}

// A GPS outage: fixes at 0 and 0.2 s, then none until 10 s. Steps inside the short interval are
// interpolated; a step in the outage has no truth (a straight line is not where the vehicle
// was), unless the caller allows a longer gap.
TEST(RobotLog, TruthIsNotInterpolatedAcrossOutages) {
  const RobotLog log = parse(R"(initial 0.0 0 0 0 0.1 0.1 0.02
control 0.1 1.0 0.0
control 5.0 1.0 0.0
truth 0.0 0.0 0.0
truth 0.2 0.2 0.0
truth 10.0 10.0 0.0
)");
  const StepSchedule s = make_schedule(log, 0.0, 0.0125);
  ASSERT_EQ(s.steps.size(), 2u);
  const TruthTrack t = interpolate_truth(log, s);
  EXPECT_NEAR(t.position[0](0), 0.1, 1e-12);
  EXPECT_TRUE(std::isnan(t.position[1](0)));
  const TruthTrack loose = interpolate_truth(log, s, 60.0);
  EXPECT_NEAR(loose.position[1](0), 5.0, 1e-12);
  EXPECT_THROW(interpolate_truth(log, s, 0.0), InvalidArgument);
}

struct BadCase {
  const char* text;
  const char* expected;  // substring of the message
};

TEST(RobotLog, RejectsMalformedInputNamingLineAndField) {
  const BadCase cases[] = {
      {"control 0.1 2.0\n", "test.log:1: record 'control': expected 'control t u1 u2'"},
      {"control 0.1 2.0 nan\n", "test.log:1: field 'u2': expected a finite number, got 'nan'"},
      {"control 0.1 2.0 0.1\ncontrol 0.1 2.0 0.1\n",
       "test.log:2: field 'time': expected a time after 0.1"},
      {"truth 1 0 0\ntruth 0.5 0 0\n", "test.log:2: field 'time'"},
      {"landmark 1 0 0\nscan 1 1\nobs 2.0 0.5 4\n",
       "test.log:3: field 'id': expected a landmark id"},
      {"landmark 1 0 0\nlandmark 1 2 2\n", "test.log:2: field 'id': expected a new landmark id"},
      {"landmark -3 0 0\n", "test.log:1: field 'id': expected a non-negative integer, got '-3'"},
      {"scan 1 2\nobs 1 0.5\n", "expected 1 more 'obs' line(s), got the end of the file"},
      {"scan 1 1\nobs 1 0.5\nobs 2 0.5\n", "test.log:3: expected an 'obs' line only after"},
      {"scan 1 2\nobs 1 0.5\ncontrol 1 1 1\n", "test.log:3: expected 1 more 'obs' line(s)"},
      {"scan 1 1\nobs -1 0.5\n", "test.log:2: field 'range': expected >= 0, got -1"},
      {"velocity 1 2 3\n",
       "test.log:1: expected a record kind vehicle|landmark|initial|control|scan|obs|truth|map|"
       "laser_mount|odometry|laser, got 'velocity'"},
      {"initial 0 0 0 0 0.1 -0.1 0.1\n", "test.log:1: field 'std_y': expected a non-negative"},
      {"truth 1 0 inf\n", "test.log:1: field 'y': expected a finite number, got 'inf'"},
  };
  for (const BadCase& c : cases) {
    try {
      parse(c.text);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos)
          << "message: " << e.what() << "\nexpected to contain: " << c.expected;
    }
  }
}

// The Car Park CSV reader on damaged copies of the bundled files.
class CarParkBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() /
        ("implicit_carpark_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    for (const auto& f : std::filesystem::directory_iterator(default_carpark_dir()))
      if (f.path().extension() == ".csv" || f.path().extension() == ".gz")
        std::filesystem::copy_file(f.path(), dir_ / f.path().filename());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  // Replaces line `line` (1-based) of `file` with `text`.
  void replace_line(const std::string& file, int line, const std::string& text) {
    std::ifstream in(dir_ / file);
    std::stringstream out;
    std::string l;
    for (int k = 1; std::getline(in, l); ++k) out << (k == line ? text : l) << "\n";
    in.close();
    std::ofstream(dir_ / file) << out.str();
  }
  std::string message() {
    try {
      load_carpark(dir_);
    } catch (const ParseError& e) {
      return e.what();
    }
    return "no error";
  }
  std::filesystem::path dir_;
};

TEST_F(CarParkBadInput, MissingColumn) {
  replace_line("carpark_gps.csv", 1, "time_s,east_m");
  EXPECT_NE(message().find("carpark_gps.csv:1: missing column 'north_m'"), std::string::npos)
      << message();
}

TEST_F(CarParkBadInput, NaNValue) {
  replace_line("carpark_dr.csv", 5, "45.124,nan,0.1");
  EXPECT_NE(
      message().find("carpark_dr.csv:5: field 'speed_mps': expected a finite number, got 'nan'"),
      std::string::npos)
      << message();
}

TEST_F(CarParkBadInput, NonMonotonicTime) {
  replace_line("carpark_gps.csv", 4, "45.0,1,2");
  EXPECT_NE(message().find("carpark_gps.csv:4: field 'time_s': expected a time after"),
            std::string::npos)
      << message();
}

TEST_F(CarParkBadInput, ShortRow) {
  replace_line("carpark_beacons.csv", 3, "2,9.9");
  EXPECT_NE(message().find("carpark_beacons.csv:3: expected 3 fields, got 2"), std::string::npos)
      << message();
}

// A beacon id beyond int: converting it was undefined behaviour (found by fuzz_carpark).
TEST_F(CarParkBadInput, BeaconIdBeyondIntIsRefused) {
  replace_line("carpark_beacons.csv", 3, "2224000000000000,9.9,1.0");
  EXPECT_NE(message().find("carpark_beacons.csv:3: field 'id': expected a new integer id in [0, "
                           "2147483647], got 2224000000000000"),
            std::string::npos)
      << message();
}

TEST_F(CarParkBadInput, GzippedFilesAreReadTransparently) {
  const CarParkData plain = load_carpark(dir_);
  for (const char* name : {"carpark_dr.csv", "carpark_laser_range_cm.csv"}) {
    write_gzip(dir_ / (std::string(name) + ".gz"), read_bytes(dir_ / name));
    std::filesystem::remove(dir_ / name);
  }
  const CarParkData zipped = load_carpark(dir_);
  EXPECT_EQ(zipped.control_time, plain.control_time);
  EXPECT_EQ(zipped.encoder_speed, plain.encoder_speed);
  EXPECT_EQ(zipped.steering, plain.steering);
  ASSERT_EQ(zipped.scans.size(), plain.scans.size());
  for (std::size_t k = 0; k < plain.scans.size(); k += 31)
    EXPECT_EQ(zipped.scans[k].range, plain.scans[k].range) << k;
  // A truncated compressed file names itself and the line where the data stop.
  const std::string bytes = read_bytes(dir_ / "carpark_dr.csv.gz");
  write_bytes(dir_ / "carpark_dr.csv.gz", bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(message().find("carpark_dr.csv.gz:"), std::string::npos) << message();
  EXPECT_NE(message().find("expected a complete gzip stream"), std::string::npos) << message();
}

TEST_F(CarParkBadInput, MissingFile) {
  std::filesystem::remove(dir_ / "carpark_laser_intensity.csv");
  EXPECT_NE(message().find("carpark_laser_intensity.csv: cannot open"), std::string::npos)
      << message();
}

}  // namespace
}  // namespace implicit::robot
