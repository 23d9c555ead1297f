// `implicit map --data BAG`: the map of a fixture bag (written by writers that are not the
// project's, tests/data/bags/README.md) is, cell by cell, the map of the CARMEN log `implicit
// convert` writes from the same bag, for the poses of the odometry (with a warning that they
// drift) and of a geometry_msgs/PoseStamped topic (--pose-topic); and the pose topic's and the
// bag flags' bad values are refused naming them.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

const std::string kMapBagDir = std::string(IMPLICIT_SOURCE_DIR) + "/tests/data/bags/";

/// A PGM image read by hand: width, height and the grey value of every pixel, row by row.
struct MapBagImage {
  int width = 0, height = 0;
  std::vector<int> pixels;
};

MapBagImage map_bag_read_pgm(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string magic;
  MapBagImage image;
  int max_value = 0;
  in >> magic >> image.width >> image.height >> max_value;
  in.get();  // the single blank after the header
  EXPECT_TRUE(magic == "P5" || magic == "P2") << file;
  EXPECT_EQ(max_value, 255) << file;
  for (int k = 0; k < image.width * image.height; ++k) {
    int v = 0;
    if (magic == "P5") {
      v = static_cast<unsigned char>(in.get());
    } else {
      in >> v;
    }
    image.pixels.push_back(v);
  }
  EXPECT_TRUE(in.good()) << file << ": shorter than its header";
  return image;
}

/// The YAML's lines but the image's name (the two maps' files have different names).
std::string map_bag_yaml(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string kept;
  for (std::string line; std::getline(in, line);)
    if (line.rfind("image:", 0) != 0) kept += line + "\n";
  return kept;
}

/// Maps `bag` directly and through `implicit convert` (the same topic flags), and checks the two
/// agree cell by cell; returns the direct run's JSON and stderr.
std::pair<nlohmann::json, std::string> map_bag_compare(const TempDir& dir, const std::string& bag,
                                                       const std::string& direct_flags,
                                                       const std::string& convert_flags) {
  const std::string stem = (dir.path() / bag).string();
  const auto c = run_cli("convert --json --data " + kMapBagDir + bag + " --out " + stem + ".log" +
                         convert_flags);
  EXPECT_EQ(c.code, 0) << c.err;
  const auto from_log =
      run_cli("map --json --resolution 0.1 --data " + stem + ".log --out " + stem + "_log.yaml");
  EXPECT_EQ(from_log.code, 0) << from_log.err;
  const auto direct = run_cli("map --json --resolution 0.1 --data " + kMapBagDir + bag + " --out " +
                              stem + "_bag.yaml" + direct_flags);
  EXPECT_EQ(direct.code, 0) << direct.err;
  if (c.code != 0 || from_log.code != 0 || direct.code != 0) return {};
  const MapBagImage a = map_bag_read_pgm(stem + "_log.pgm");
  const MapBagImage b = map_bag_read_pgm(stem + "_bag.pgm");
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(map_bag_yaml(stem + "_log.yaml"), map_bag_yaml(stem + "_bag.yaml"));
  const auto jc = nlohmann::json::parse(c.out);
  const auto jl = nlohmann::json::parse(from_log.out);
  const auto jb = nlohmann::json::parse(direct.out);
  EXPECT_EQ(jb["scans"], jc["scans"]);
  EXPECT_EQ(jb["scans_outside_poses"], jc["scans_outside_odometry"]);
  EXPECT_EQ(jl["poses"], "log");
  for (const char* key : {"occupied", "free", "unknown", "width", "height", "origin", "mount"})
    EXPECT_EQ(jb[key], jl[key]) << key;
  // Not an empty picture: the 30 scans of the Intel lab see walls.
  EXPECT_GT(jb["occupied"].get<int>(), 50);
  return {jb, direct.err};
}

TEST(MapBagCli, BagAndItsConvertedLogGiveTheSameMap) {
  TempDir dir("map_bag_cli");
  for (const std::string bag : {"intel-zstd.mcap", "intel-rosbag2", "intel-lz4.bag"}) {
    SCOPED_TRACE(bag);
    const auto [odometry, warning] = map_bag_compare(dir, bag, "", "");
    EXPECT_EQ(odometry["poses"], "odometry");
    EXPECT_EQ(odometry["scans"], 30);
    EXPECT_NE(warning.find("warning: no --pose-topic: the map of"), std::string::npos) << warning;
    EXPECT_NE(warning.find("raw odometry of /odom, which drifts"), std::string::npos) << warning;
    const auto [truth, quiet] =
        map_bag_compare(dir, bag, " --pose-topic /ground_truth", " --odom-topic /ground_truth");
    EXPECT_EQ(truth["poses"], "/ground_truth");
    EXPECT_EQ(truth["scans"], 30);
    EXPECT_EQ(truth["scans_outside_poses"], 0);
    EXPECT_EQ(quiet.find("warning"), std::string::npos) << quiet;
  }
  // The text summary says where the poses came from and how many scans were left out.
  const auto text = run_cli("map --data " + kMapBagDir + "intel-zstd.mcap --out " +
                            (dir.path() / "t.yaml").string() + " --pose-topic /ground_truth");
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("poses from /ground_truth; 0 scans left out"), std::string::npos)
      << text.out;
}

TEST(MapBagCli, BadPoseTopicsAndBagFlagsAreRefusedNamingThem) {
  TempDir dir("map_bag_cli_bad");
  const std::string out = " --out " + (dir.path() / "m.yaml").string();
  const std::string mcap = "map --data " + kMapBagDir + "intel-zstd.mcap" + out;
  const std::string aces =
      "map --data " + std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz" + out;
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const Row rows[] = {
      {mcap + " --pose-topic /nope", 1,
       "intel-zstd.mcap: expected topic '/nope' (--pose-topic), got no such topic; the bag has: "},
      {mcap + " --pose-topic /odom", 1,
       "topic '/odom' (--pose-topic): expected messages of type geometry_msgs/PoseStamped, got "
       "'nav_msgs/msg/Odometry'"},
      {mcap + " --pose-topic ''", 2, "--pose-topic"},
      {mcap + " --scan-topic /nope", 1, "expected topic '/nope' (--scan-topic)"},
      {mcap + " --scan-topic /nope --pose-topic /ground_truth", 1,
       "expected topic '/nope' (--scan-topic)"},
      {mcap + " --odom-topic /tf", 1, "topic '/tf' (--odom-topic)"},
      {"map --data " + kMapBagDir + "backwards.mcap" + out, 1,
       "backwards.mcap: topic '/scan' message 20: header.stamp"},
      {aces + " --pose-topic /ground_truth", 1, "map --pose-topic: applies to a ROS bag as --data"},
      {aces + " --scan-topic /scan", 1, "map --scan-topic: applies to a ROS bag as --data"},
      {aces + " --laser-frame laser", 1, "map --laser-frame: applies to a ROS bag as --data"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_EQ(r.out, "") << row.args;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
