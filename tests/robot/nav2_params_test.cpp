// robot::parse_nav2_parameters: one node's ros__parameters from a ROS 2 parameter file.
#include <gtest/gtest.h>

#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/nav2_params.hpp"

namespace {

using implicit::ParseError;
using implicit::robot::parse_nav2_parameters;

std::string nav2_params_error(const std::string& text) {
  try {
    parse_nav2_parameters(text, "p.yaml", "amcl");
  } catch (const ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(Nav2Params, ReadsOneNodesBlockWithLinesNestingAndLists) {
  const std::string text =
      "bt_navigator:\n"
      "  ros__parameters:\n"
      "    z_hit: 9.0\n"
      "/robot1/amcl:\n"
      "  ros__parameters:\n"
      "    z_hit: 0.5\n"
      "    laser_model_type: \"likelihood_field\"\n"
      "    initial_pose: {x: 1.0, yaw: 0.5}\n"
      "    ranges: [1, 2, 3]\n"
      "    empty:\n";
  const auto p = parse_nav2_parameters(text, "p.yaml", "amcl");
  EXPECT_EQ(p.node, "/robot1/amcl");
  ASSERT_EQ(p.entries.size(), 6u);
  ASSERT_NE(p.find("z_hit"), nullptr);
  EXPECT_EQ(p.find("z_hit")->value, "0.5");  // amcl's, not bt_navigator's
  EXPECT_EQ(p.find("z_hit")->line, 6);
  EXPECT_EQ(p.find("laser_model_type")->value, "likelihood_field");
  EXPECT_EQ(p.find("initial_pose.x")->value, "1.0");
  EXPECT_EQ(p.find("initial_pose.yaw")->value, "0.5");
  EXPECT_TRUE(p.find("ranges")->is_list);
  EXPECT_EQ(p.find("ranges")->value, "1 2 3");
  EXPECT_EQ(p.find("empty")->value, "");
  EXPECT_EQ(p.find("nope"), nullptr);
  // The wildcard namespace of ROS 2 names the node too.
  EXPECT_EQ(parse_nav2_parameters("/**/amcl:\n  ros__parameters:\n    a: 1\n", "p", "amcl").node,
            "/**/amcl");
}

TEST(Nav2Params, BadFilesNameTheFileTheLineAndWhatIsWrong) {
  struct Nav2BadFile {
    std::string text, says;
  };
  const Nav2BadFile rows[] = {
      {"", "p.yaml: expected a ROS 2 parameter file with a 'amcl:' block"},
      {"amcl: [1\n", "p.yaml:"},
      {"- a\n- b\n", "got a list or a single value"},
      {"controller_server:\n  ros__parameters:\n    a: 1\n", "got no 'amcl' block"},
      {"amcl:\n  z_hit: 0.5\n", "p.yaml:1: amcl: expected 'ros__parameters:'"},
      {"amcl:\n  ros__parameters: [1, 2]\n", "p.yaml:2: amcl: ros__parameters: expected a mapping"},
      {"amcl:\n  ros__parameters:\n    z_hit: 0.5\n    z_hit: 0.6\n",
       "p.yaml:4: z_hit: the key is given twice"},
      {"amcl:\n  ros__parameters:\n    a: [[1]]\n", "p.yaml:3: a: expected a list of numbers"},
      {"amcl:\n  ros__parameters:\n    a: {b: {c: {d: {e: {f: {g: {h: {i: {j: 1}}}}}}}}}\n",
       "levels of nesting"},
  };
  for (const auto& row : rows) {
    const std::string e = nav2_params_error(row.text);
    EXPECT_NE(e.find(row.says), std::string::npos) << row.text << "\n" << e;
  }
}

}  // namespace
