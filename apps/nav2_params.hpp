#pragma once
// `implicit mcl --params amcl.yaml`: a nav2 parameter file's AMCL block as the laser run's flags
// (docs/cli.md, "nav2 AMCL parameters"). Each key that means the same here sets its flag, unless
// that flag is on the command line (the command line wins); a key without a meaning here is
// named once on stderr; a value the flag refuses ends the command, naming the file, line and key.

#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
}

namespace implicit::app {

struct Nav2ParamsRecord {
  std::string file;
  std::vector<std::pair<std::string, std::string>> used;  ///< key -> "flag value" it set
  std::vector<std::string> overridden;                    ///< keys whose flag the command line gave
  std::vector<std::string> not_used;  ///< keys without a meaning here (warned on stderr)
};

/// Applies `file`'s `amcl` block to the options of the mcl subcommand `sub`. `bag_data`: --data
/// is a ROS bag (the topic and frame keys apply only then). Throws InvalidArgument for a file
/// that cannot be read or has no amcl block, and for a value its flag refuses or that this
/// program cannot run (an omnidirectional robot, beam skipping).
Nav2ParamsRecord apply_nav2_params(CLI::App& sub, const std::string& file, bool bag_data);

}  // namespace implicit::app
