#pragma once
// The flags that choose a ROS bag's topics and frames (robot/bag.hpp), shared by `implicit mcl
// --sensor laser` and `implicit convert`.
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "implicit/robot/bag.hpp"

namespace implicit::app {

struct BagFlags {
  robot::BagOptions options;
  std::vector<CLI::Option*> given;  ///< the flags, to tell whether any was given
};

/// Adds --scan-topic, --odom-topic, --base-frame and --laser-frame to `sub`.
void add_bag_flags(CLI::App& sub, BagFlags& flags);

/// Refuses bag flags with a --data that is not a ROS bag (they would be ignored); `command` names
/// the subcommand in the message.
void require_bag_for_flags(const BagFlags& flags, const std::string& data,
                           std::string_view command);

}  // namespace implicit::app
