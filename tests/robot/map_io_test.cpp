// ROS map_server map files: exact round trips, hand-written maps in every mode and image kind,
// and every malformed file refused with a message naming it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/map_io.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

class MapFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           fmt::format("implicit-map-io-{}-{}", ::getpid(),
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& content) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  fs::path dir_;
};

const char* const kTinyYaml =
    "image: tiny.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\n"
    "occupied_thresh: 0.65\nfree_thresh: 0.196\n";

// Three columns, two rows; the first row is the top of the map (the higher y).
const char* const kTinyPgm =
    "P2\n# a comment\n3 2\n255\n"
    "0 254 205\n"
    "255 100 0\n";

TEST_F(MapFiles, LoadsAHandWrittenPlainPgmTopRowHighestY) {
  write("tiny.pgm", kTinyPgm);
  const OccupancyGrid g = load_map(write("tiny.yaml", kTinyYaml));
  ASSERT_EQ(g.width(), 3);
  ASSERT_EQ(g.height(), 2);
  EXPECT_EQ(g.resolution(), 0.5);
  EXPECT_EQ(g.origin(), Vec<2>(1.0, -2.0));
  // p = (255 - v) / 255: 0 -> 1 (occupied), 254 -> 0.004 and 255 -> 0 (free), 205 -> 0.196
  // and 100 -> 0.608 (between the thresholds: unknown).
  EXPECT_EQ(g.at(0, 1), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.at(1, 1), OccupancyGrid::kFree);
  EXPECT_EQ(g.at(2, 1), OccupancyGrid::kUnknown);
  EXPECT_EQ(g.at(0, 0), OccupancyGrid::kFree);
  EXPECT_EQ(g.at(1, 0), OccupancyGrid::kUnknown);
  EXPECT_EQ(g.at(2, 0), OccupancyGrid::kOccupied);
  // The top-left pixel covers x in [1, 1.5), y in [-1.5, -1).
  EXPECT_EQ(g.cell_of(Vec<2>(1.2, -1.2)), Eigen::Vector2i(0, 1));
  // The image path is relative to the YAML file's folder, not to the working directory.
  EXPECT_EQ(parse_map(kTinyYaml, kTinyPgm, "elsewhere/tiny.yaml").data().size(), 6u);
}

TEST_F(MapFiles, NegateScaleAndRawModes) {
  // negate: p = v / 255, so black is free and white occupied.
  const std::string pgm = "P2 4 1 255 0 255 100 200";
  const std::string base =
      "image: m.pgm\nresolution: 1\norigin: [0, 0, 0]\noccupied_thresh: 0.75\nfree_thresh: 0.25\n";
  const OccupancyGrid neg = parse_map(base + "negate: 1\n", pgm, "m.yaml");
  EXPECT_EQ(neg.at(0, 0), 0);
  EXPECT_EQ(neg.at(1, 0), 100);
  EXPECT_EQ(neg.at(2, 0), -1);   // 100 / 255 = 0.39
  EXPECT_EQ(neg.at(3, 0), 100);  // 200 / 255 = 0.78
  // scale: round(99 (p - 0.25) / 0.5) between the thresholds. Pixel 128: p = 127/255 =
  // 0.49804, 99 * 0.49608 = 49.11 -> 49. Pixel 64: p = 0.74902 -> 98.81 -> 99. Pixel 63:
  // p = 0.75294 > 0.75 -> 100. Pixel 192: p = 0.24706 < 0.25 -> 0.
  const OccupancyGrid scale =
      parse_map(base + "negate: false\nmode: scale\n", "P2 4 1 255 128 64 63 192", "m.yaml");
  EXPECT_EQ(scale.at(0, 0), 49);
  EXPECT_EQ(scale.at(1, 0), 99);
  EXPECT_EQ(scale.at(2, 0), 100);
  EXPECT_EQ(scale.at(3, 0), 0);
  // raw: the pixel is the value; 255 is unknown.
  const OccupancyGrid raw =
      parse_map(base + "negate: 0\nmode: raw\n", "P2 4 1 255 0 37 100 255", "m.yaml");
  EXPECT_EQ(raw.at(0, 0), 0);
  EXPECT_EQ(raw.at(1, 0), 37);
  EXPECT_EQ(raw.at(2, 0), 100);
  EXPECT_EQ(raw.at(3, 0), -1);
  // With negate, raw reads 255 - v (as map_server does).
  const OccupancyGrid raw_neg =
      parse_map(base + "negate: 1\nmode: raw\n", "P2 2 1 255 255 200", "m.yaml");
  EXPECT_EQ(raw_neg.at(0, 0), 0);
  EXPECT_EQ(raw_neg.at(1, 0), 55);
}

TEST_F(MapFiles, BinaryPgmOf8And16Bits) {
  const std::string yaml =
      "image: b.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
      "free_thresh: 0.196\n";
  std::string p8 = "P5\n2 2\n255\n";
  p8 += std::string("\x00\xff\xcd\x80", 4);  // top row 0, 255; bottom row 205, 128
  const OccupancyGrid g8 = parse_map(yaml, p8, "b.yaml");
  EXPECT_EQ(g8.at(0, 1), 100);
  EXPECT_EQ(g8.at(1, 1), 0);
  EXPECT_EQ(g8.at(0, 0), -1);
  EXPECT_EQ(g8.at(1, 0), -1);  // p = 127 / 255 = 0.498
  // 16 bits, big-endian: p = (65535 - v) / 65535. 0 -> 1, 65535 -> 0, 0x1000 = 4096 -> 0.9375,
  // 0xd000 = 53248 -> 0.1875.
  std::string p16 = "P5 4 1 65535\n";
  p16 += std::string("\x00\x00\xff\xff\x10\x00\xd0\x00", 8);
  const OccupancyGrid g16 = parse_map(yaml, p16, "b.yaml");
  EXPECT_EQ(g16.at(0, 0), 100);
  EXPECT_EQ(g16.at(1, 0), 0);
  EXPECT_EQ(g16.at(2, 0), 100);
  EXPECT_EQ(g16.at(3, 0), 0);
  // A maxval below 255 scales too: with maxval 10, v = 5 is p = 0.5 (unknown), 9 is 0.1 (free).
  const OccupancyGrid g10 = parse_map(yaml, "P2 2 1 10 5 9", "b.yaml");
  EXPECT_EQ(g10.at(0, 0), -1);
  EXPECT_EQ(g10.at(1, 0), 0);
}

TEST_F(MapFiles, RoundTripIsExactAndLeavesNoTemporaryFiles) {
  Rng rng({51, 0, 0, purpose::kUser});
  OccupancyGrid g(37, 23, 0.05, Vec<2>(-12.345678901234567, 6.7));
  for (auto& c : g.data()) {
    const double u = rng.uniform();
    c = u < 0.3   ? OccupancyGrid::kOccupied
        : u < 0.7 ? OccupancyGrid::kFree
                  : OccupancyGrid::kUnknown;
  }
  save_map(g, dir_ / "copy.yaml");
  EXPECT_TRUE(fs::exists(dir_ / "copy.pgm"));
  int files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 2);
  const OccupancyGrid back = load_map(dir_ / "copy.yaml");
  EXPECT_EQ(back.width(), g.width());
  EXPECT_EQ(back.height(), g.height());
  EXPECT_EQ(back.resolution(), g.resolution());
  EXPECT_EQ(back.origin(), g.origin());
  EXPECT_TRUE(std::equal(g.data().begin(), g.data().end(), back.data().begin()));
  // Saving over an existing map replaces it.
  g.at(0, 0) = OccupancyGrid::kOccupied;
  save_map(g, dir_ / "copy.yaml");
  EXPECT_EQ(load_map(dir_ / "copy.yaml").at(0, 0), OccupancyGrid::kOccupied);
  // A file name that needs quoting in YAML.
  save_map(g, dir_ / "a map: \"x\" #1.yaml");
  EXPECT_TRUE(std::equal(g.data().begin(), g.data().end(),
                         load_map(dir_ / "a map: \"x\" #1.yaml").data().begin()));
}

TEST_F(MapFiles, IntermediateValuesSaveAsGreysThatKeepTheirClass) {
  OccupancyGrid g(102, 1, 1.0, Vec<2>::Zero());
  for (int c = -1; c <= 100; ++c) g.at(c + 1, 0) = static_cast<std::int8_t>(c);
  save_map(g, dir_ / "grey.yaml");
  const OccupancyGrid back = load_map(dir_ / "grey.yaml");
  for (int ix = 0; ix < 102; ++ix) {
    const int expected = g.is_occupied(ix, 0) ? 100 : g.is_free(ix, 0) ? 0 : -1;
    EXPECT_EQ(back.at(ix, 0), expected) << "value " << int(g.at(ix, 0));
  }
}

TEST_F(MapFiles, SaveRefusesEmptyGridsAndUnwritableFolders) {
  try {
    save_map(OccupancyGrid(), dir_ / "e.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("expected a grid with cells, got an empty one"));
  }
  const OccupancyGrid g(2, 2, 1.0, Vec<2>::Zero());
  try {
    save_map(g, dir_ / "no" / "such" / "folder.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("save_map: expected a writable file"));
  }
  EXPECT_THROW(save_map(g, dir_ / "same.pgm"), InvalidArgument);
}

// The message of the ParseError (or InvalidArgument) parse_map throws.
std::string map_error(const std::string& yaml, const std::string& pgm) {
  try {
    parse_map(yaml, pgm, "maps/bad.yaml");
  } catch (const ParseError& e) {
    return e.what();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

std::string yaml_with(const std::string& key, const std::string& line) {
  std::string out;
  const char* keys[][2] = {{"image", "image: bad.pgm"},
                           {"resolution", "resolution: 0.05"},
                           {"origin", "origin: [0, 0, 0]"},
                           {"negate", "negate: 0"},
                           {"occupied_thresh", "occupied_thresh: 0.65"},
                           {"free_thresh", "free_thresh: 0.196"}};
  for (const auto& [k, l] : keys) out += (k == key ? line : std::string(l)) + "\n";
  return out;
}

TEST(MapFormat, MalformedYamlIsRefusedNamingFileLineAndKey) {
  const std::string pgm = "P2 1 1 255 0";
  struct Case {
    std::string yaml, expected;
  };
  const Case cases[] = {
      {yaml_with("image", ""),
       "maps/bad.yaml: key 'image': expected an image file name, got "
       "nothing (the key is missing)"},
      {yaml_with("resolution", ""),
       "key 'resolution': expected a positive number (metres per "
       "pixel), got nothing (the key is missing)"},
      {yaml_with("origin", ""),
       "key 'origin': expected a list [x, y, yaw] of three numbers, "
       "got nothing"},
      {yaml_with("negate", ""), "key 'negate': expected 0 or 1, got nothing"},
      {yaml_with("occupied_thresh", ""),
       "key 'occupied_thresh': expected a number in [0, 1], "
       "got nothing"},
      {yaml_with("free_thresh", ""), "key 'free_thresh'"},
      {yaml_with("resolution", "resolution: 0"),
       "maps/bad.yaml:2: key 'resolution': expected a positive number (metres per pixel), got 0"},
      {yaml_with("resolution", "resolution: -0.05"), ":2: key 'resolution': expected a positive"},
      {yaml_with("resolution", "resolution: .nan"), "got '.nan'"},
      {yaml_with("resolution", "resolution: 5cm"), "got '5cm'"},
      {yaml_with("occupied_thresh", "occupied_thresh: 1.5"),
       ":5: key 'occupied_thresh': expected a number in [0, 1], got 1.5"},
      {yaml_with("free_thresh", "free_thresh: -0.1"),
       ":6: key 'free_thresh': expected a number in [0, 1], got -0.1"},
      {yaml_with("free_thresh", "free_thresh: 0.65"),
       ":6: key 'free_thresh': expected a value below occupied_thresh 0.65, got 0.65"},
      {yaml_with("origin", "origin: [1, 2, 0.5]"),
       ":3: key 'origin': expected a yaw of 0, got 0.5 (rotated maps are not supported"},
      {yaml_with("origin", "origin: [1, 2]"),
       "expected a list [x, y, yaw] of three numbers, "
       "got 2 values"},
      {yaml_with("origin", "origin: 3"), "got a single value"},
      {yaml_with("origin", "origin: [1, x, 0]"), "got 'x' at position 2"},
      {yaml_with("negate", "negate: 2"), ":4: key 'negate': expected 0 or 1, got '2'"},
      {yaml_with("image", "image: [a, b]"),
       "key 'image': expected an image file name, got a "
       "list or mapping"},
      {yaml_with("image", "image: ''"), "key 'image': expected an image file name, got an empty"},
      {yaml_with("", "") + "mode: ternary\n",
       ":7: key 'mode': expected trinary, scale or raw, got 'ternary'"},
      {"", "maps/bad.yaml: expected a YAML mapping with the keys image, resolution"},
      {"- a\n- b\n", "expected a YAML mapping"},
      {"image: [unclosed\n", "maps/bad.yaml:2: expected a YAML file, got a syntax error"},
  };
  for (const auto& c : cases) EXPECT_THAT(map_error(c.yaml, pgm), HasSubstr(c.expected)) << c.yaml;
  EXPECT_EQ(map_error(yaml_with("", ""), pgm), "no error");
}

TEST(MapFormat, MalformedImagesAreRefusedNamingTheImage) {
  const std::string yaml = yaml_with("", "");
  struct Case {
    std::string pgm, expected;
  };
  const Case cases[] = {
      {"", "maps/bad.pgm:1: expected a PGM image (P5 or P2), got an empty file"},
      {"\x89PNG\r\n\x1a\n....",
       "expected a PGM image (P5 or P2), got a file starting "
       "'\\x89PNG\\x0d\\x0a\\x1a\\x0a'"},
      {"P6 1 1 255\n\x01\x02\x03", "expected a greyscale PGM image (P5 or P2), got a P6 image"},
      {"P5 2 2 0\n\x01\x02\x03\x04", "field 'maxval': expected a maxval in 1..65535, got 0"},
      {"P5 2 2 70000\n\x01\x02\x03\x04", "expected a maxval in 1..65535, got 70000"},
      {"P5 2 2 255\n\x01\x02\x03",
       "expected 2 x 2 pixels of 1 byte(s) = 4 bytes of pixel "
       "data, got 3 (a truncated file)"},
      {"P5 2 2 255\n\x01\x02\x03\x04\x05", "got 5 (more than the header says)"},
      {"P5 2 1 65535\n\x01\x02\x03", "= 4 bytes of pixel data, got 3"},
      {"P5 2 1 1000\n\x03\xe8\x03\xe9",
       "pixel (row 0, column 1): expected a value <= maxval "
       "1000, got 1001"},
      {"P5 2 2", "field 'maxval': expected a number, got the end of the file"},
      {"P5 2 2 255", "expected a whitespace byte after maxval"},
      {"P5 0 2 255\n", "field 'width': expected an integer >= 1, got 0"},
      {"P5 -3 2 255\n", "field 'width': expected an integer in 0..2147483647, got '-3'"},
      {"P5 99999999999 2 255\n", "field 'width': expected an integer in 0..2147483647"},
      {"P5 3x 2 255\n", "field 'width': expected a non-negative integer, got '3x'"},
      {"P5 100000 100000 255\n\x01", "expected 100000 x 100000 pixels of 1 byte(s)"},
      {"P2\n2 2\n255\n1 2\n3\n",
       "maps/bad.pgm:6: expected 2 x 2 = 4 pixel values, got 3 (a truncated file?)"},
      {"P2\n2 1\n255\n1 2 3\n", "expected 2 x 1 = 2 pixel values, got more: '3"},
      {"P2\n2 1\n255\n1 256\n",
       "maps/bad.pgm:4: field 'pixel': expected an integer in 0..255, "
       "got '256'"},
      {"P2\n2 1\n255\n1 x\n", "field 'pixel': expected a non-negative integer, got 'x'"},
      {"P2 50000 50000 255\n1 2 3", "got a file too short for them"},
  };
  for (const auto& c : cases)
    EXPECT_THAT(map_error(yaml, c.pgm), HasSubstr(c.expected)) << printable(c.pgm);
  EXPECT_THAT(map_error(yaml_with("", "") + "mode: raw\n", "P2 2 1 255 100 101"),
              HasSubstr("maps/bad.pgm: pixel (row 0, column 1): expected a value 0..100, or 255 "
                        "for unknown, in raw mode, got 101"));
  EXPECT_THAT(map_error(yaml_with("resolution", "resolution: 1e308"), "P2 2 1 255 0 0"),
              HasSubstr("expected a map with a finite extent"));
}

TEST_F(MapFiles, MissingFilesAreNamed) {
  try {
    load_map(dir_ / "none.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("none.yaml: cannot open the file for reading"));
  }
  const fs::path yaml = write("lost.yaml", yaml_with("image", "image: lost.pgm"));
  try {
    load_map(yaml);
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("lost.yaml: key 'image': expected a readable image file, "
                                    "cannot read '" +
                                    (dir_ / "lost.pgm").string() + "'"));
  }
  // A folder where the image should be.
  fs::create_directories(dir_ / "folder.pgm");
  EXPECT_THROW(load_map(write("f.yaml", yaml_with("image", "image: folder.pgm"))), ParseError);
}

}  // namespace
}  // namespace implicit::robot
