#pragma once
// A ROS 2 parameter file (the YAML that nav2's launch files pass to its nodes), read for one
// node's `ros__parameters` block, e.g. AMCL's:
//
//   amcl:
//     ros__parameters:
//       alpha1: 0.2
//       z_hit: 0.5
//       laser_model_type: "likelihood_field"
//
//   robot::Nav2Parameters p = robot::read_nav2_parameters("nav2_params.yaml", "amcl");
//   for (const auto& e : p.entries) ...   // key, value text, line
//
// The file may hold other nodes' blocks (a whole nav2_params.yaml); they are not read. The node
// may be written with a namespace ("/robot1/amcl") or ROS 2's wildcard prefix ("/**/amcl").
// Nested mappings (initial_pose: {x: 0.0}) flatten to dotted keys ("initial_pose.x"); a list's
// value is its items separated by single spaces. What the keys mean is the caller's business.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace implicit::robot {

struct Nav2Parameter {
  std::string key;    ///< dotted for nested mappings
  std::string value;  ///< the scalar's text, or a list's items joined by spaces
  int line = 0;       ///< 1-based line of the value in the file
  bool is_list = false;
};

struct Nav2Parameters {
  std::string source;  ///< the file name, for messages
  std::string node;    ///< the node as written in the file ("amcl", "/robot1/amcl", ...)
  std::vector<Nav2Parameter> entries;  ///< in file order; each key once

  /// The entry of `key`, or nullptr.
  const Nav2Parameter* find(std::string_view key) const;
};

/// The `ros__parameters` of `node` in the parameter file `text` (named `name` in messages).
/// Throws ParseError naming the file (and line) for text that is not YAML, a file without that
/// node's block or with a block that is not a mapping, and a key given twice.
Nav2Parameters parse_nav2_parameters(std::string_view text, const std::string& name,
                                     const std::string& node);
/// As parse_nav2_parameters, from a file (InvalidArgument naming it when it cannot be read).
Nav2Parameters read_nav2_parameters(const std::filesystem::path& path, const std::string& node);

}  // namespace implicit::robot
