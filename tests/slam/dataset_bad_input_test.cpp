// Bad SLAM inputs: the vehicle comment of a robot log, a log with nothing to run, and the
// synthetic-SLAM CSV files. Each is a ParseError naming the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "implicit/core/error.hpp"
#include "implicit/slam/dataset.hpp"

namespace implicit::slam {
namespace {

class SlamBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("implicit_slam_bad_" + std::to_string(::getpid()) + "_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_ / "slam-synthetic");
  }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }
  template <typename F>
  std::string error_of(F&& f) {
    try {
      f();
    } catch (const ParseError& e) {
      return e.what();
    }
    return "no error";
  }
  std::string log_error(const std::string& text) {
    const auto path = write("run.log", text);
    return error_of([&] { read_slam_log(path); });
  }
  std::string at(int line) const {
    return (dir_ / "run.log").string() + ":" + std::to_string(line);
  }
  std::filesystem::path dir_;
};

const std::string kBody = "landmark 0 5 5\ninitial 0 0 0 0 0 0 0\ncontrol 0.025 1 0\n";

TEST_F(SlamBadInput, VehicleCommentWithNanIsAnErrorNamingTheLine) {
  EXPECT_EQ(log_error("# vehicle dt=0.025 a=nan\n" + kBody),
            at(1) + ": vehicle comment: field 'a': expected an offset in [-100, 100] m, got 'nan'");
}

TEST_F(SlamBadInput, VehicleCommentWithHugeTimeStepIsAnErrorNamingTheLine) {
  EXPECT_EQ(
      log_error(kBody + "# vehicle dt=1e300\n"),
      at(4) + ": vehicle comment: field 'dt': expected a time step in (0, 60] s, got '1e300'");
  EXPECT_EQ(log_error("# vehicle L=0\n" + kBody),
            at(1) + ": vehicle comment: field 'L': expected a wheelbase in (0, 100] m, got '0'");
  EXPECT_EQ(log_error("# vehicle zz=500\n" + kBody),
            at(1) + ": vehicle comment: expected dt|L|H|a|b, got 'zz'");
  EXPECT_EQ(log_error("# vehicle dt=0.05 L=2.83 H=0.76 a=0.95 b=0.5\n" + kBody), "no error");
}

// The record and the older comment share one range check: the same value, the same expectation.
TEST_F(SlamBadInput, VehicleRecordHasTheRangesOfTheComment) {
  for (const std::string kv : {"a=150", "L=1e300", "dt=100", "H=-200"}) {
    SCOPED_TRACE(kv);
    const std::string comment = log_error("# vehicle " + kv + "\n" + kBody);
    const std::string record = log_error("vehicle ute " + kv + "\n" + kBody);
    const std::string tail = comment.substr(comment.find(": field '"));
    EXPECT_EQ(comment, at(1) + ": vehicle comment" + tail);
    EXPECT_EQ(record, at(1) + tail);
  }
}

// `mcl` refused a key its model does not have; `slam` ignored it for every model but the Ute.
TEST_F(SlamBadInput, VehicleRecordWithAKeyTheModelLacksIsRefused) {
  const auto path = write("run.log", "vehicle unicycle dt=0.1 L=2\n" + kBody);
  try {
    read_slam_log(path);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              path.string() + ": vehicle 'unicycle': expected parameters among dt, got 'L'");
  }
  EXPECT_EQ(read_slam_log(write("run.log", "vehicle unicycle dt=0.1\n" + kBody)).vehicle.dt, 0.1);
}

// Which logs leave the vehicle to be assumed: neither a record nor the older comment.
TEST_F(SlamBadInput, VehicleIsAssumedOnlyWhenTheLogDeclaresNone) {
  EXPECT_TRUE(read_slam_log(write("run.log", kBody)).vehicle_assumed);
  EXPECT_FALSE(read_slam_log(write("run.log", "# vehicle dt=0.05\n" + kBody)).vehicle_assumed);
  EXPECT_FALSE(read_slam_log(write("run.log", "vehicle ute dt=0.05\n" + kBody)).vehicle_assumed);
  EXPECT_FALSE(
      read_slam_log(write("run.log", "vehicle unicycle dt=0.05\n" + kBody)).vehicle_assumed);
}

TEST_F(SlamBadInput, LogWithNoControlsIsAnErrorNamingTheLine) {
  EXPECT_EQ(log_error("initial 1 0 0 0 0 0 0\nscan 0.5 0\n"),
            at(1) +
                ": expected 'control' records at or after the 'initial' time 1, got none in "
                "the file");
}

TEST_F(SlamBadInput, SyntheticCsvShortRowIsAParseErrorNamingTheLine) {
  write("slam-synthetic/carpark_controls.csv", "vc,alpha\n1,0\n");
  write("slam-synthetic/landmarks.csv", "id,east_m,north_m\n0,1,2\n1,3\n");
  EXPECT_EQ(error_of([&] { load_carpark_scenario(dir_); }),
            (dir_ / "slam-synthetic/landmarks.csv").string() + ":3: expected 3 fields, got 2");
  const auto trace = write("trace.csv", "x_hat,y_hat,beta_hat\n1,2,3\n4,5\n");
  EXPECT_EQ(error_of([&] { read_reference_trace(trace); }),
            trace.string() + ":3: expected 3 fields, got 2");
}

TEST_F(SlamBadInput, SyntheticCsvNonFiniteLandmarkIsRejected) {
  write("slam-synthetic/carpark_controls.csv", "vc,alpha\n1,0\n");
  const auto landmarks = dir_ / "slam-synthetic/landmarks.csv";
  for (const char* bad : {"inf", "-inf", "1e999", "nan"}) {
    write("slam-synthetic/landmarks.csv", std::string("id,east_m,north_m\n0,1,") + bad + "\n");
    EXPECT_NE(error_of([&] {
                load_carpark_scenario(dir_);
              }).find(landmarks.string() + ":2: field 'north_m': expected a"),
              std::string::npos)
        << bad;
  }
  write("slam-synthetic/landmarks.csv", "id,east_m,north_m\n0,1,2\n");
  EXPECT_EQ(error_of([&] { load_carpark_scenario(dir_); }), "no error");
}

}  // namespace
}  // namespace implicit::slam
