// ROS bags on the command line: `implicit mcl --sensor laser --data BAG` gives the same result as
// the CARMEN log `implicit convert` writes from it, for an MCAP file and a rosbag2 folder; and
// the bag flags' bad values, missing topics and wrong data are refused naming them.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

const std::string kBagCliDir = std::string(IMPLICIT_SOURCE_DIR) + "/tests/data/bags/";

std::string bag_cli_mcl(const std::string& data) {
  return "mcl --sensor laser --quiet --json --runs 1 -M 10 --max-updates 8 --map-resolution 0.1 "
         "--data " +
         data;
}

/// The scores of a laser MCL run's JSON (not its timing or its file name).
nlohmann::json bag_cli_scores(const std::string& out) {
  const auto j = nlohmann::json::parse(out);
  return {j["updates"],
          j["scored_updates"],
          j["map"],
          j["position_rmse_m"],
          j["heading_rmse_rad"],
          j["ess_fraction"],
          j["lost_runs"],
          j["per_run"][0]["position_rmse_m"]};
}

TEST(BagCli, BagAndItsConvertedLogGiveTheSameRun) {
  TempDir dir("bag_cli");
  for (const std::string bag : {"intel-zstd.mcap", "intel-rosbag2"}) {
    SCOPED_TRACE(bag);
    const std::string log = (dir.path() / (bag + ".log.gz")).string();
    const auto c = run_cli("convert --json --data " + kBagCliDir + bag + " --out " + log);
    ASSERT_EQ(c.code, 0) << c.err;
    const auto j = nlohmann::json::parse(c.out);
    EXPECT_EQ(j["scans"], 30);
    EXPECT_EQ(j["odometry"], 31);
    EXPECT_EQ(j["base_frame"], "base_footprint");
    EXPECT_EQ(j["laser_frame"], "laser");
    EXPECT_TRUE(j["mount_from_tf"].get<bool>());
    const auto direct = run_cli(bag_cli_mcl(kBagCliDir + bag));
    ASSERT_EQ(direct.code, 0) << direct.err;
    const auto converted = run_cli(bag_cli_mcl(log));
    ASSERT_EQ(converted.code, 0) << converted.err;
    EXPECT_EQ(bag_cli_scores(direct.out), bag_cli_scores(converted.out));
    EXPECT_EQ(nlohmann::json::parse(direct.out)["updates"], 8);
  }
}

TEST(BagCli, BadTopicsFramesAndDataAreRefusedNamingThem) {
  TempDir dir("bag_cli_bad");
  const std::string mcap = kBagCliDir + "intel-zstd.mcap";
  const std::string aces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const Row rows[] = {
      {bag_cli_mcl(mcap) + " --scan-topic /nope", 1,
       "intel-zstd.mcap: expected topic '/nope' (--scan-topic), got no such topic"},
      {bag_cli_mcl(mcap) + " --odom-topic /tf", 1,
       "topic '/tf' (--odom-topic): expected messages of type nav_msgs/Odometry or "
       "geometry_msgs/PoseStamped, got 'tf2_msgs/msg/TFMessage'"},
      {bag_cli_mcl(kBagCliDir + "backwards.mcap"), 1,
       "backwards.mcap: topic '/scan' message 20: header.stamp"},
      {bag_cli_mcl(mcap) + " --base-frame ''", 2, "--base-frame"},
      {bag_cli_mcl(aces) + " --laser-frame laser", 1,
       "mcl --sensor laser --laser-frame: applies to a ROS bag as --data"},
      {"convert --data " + aces + " --out " + (dir.path() / "x.log").string(), 1,
       "convert --data: expected a ROS bag"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
