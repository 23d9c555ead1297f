#pragma once
// --trajectory and --truth-trajectory of mcl and slam: a run's estimate (or the reference it is
// scored against) as a TUM file (t x y z qx qy qz qw, docs/formats.md), the input of
// `implicit eval` and of evo. Planar poses embed as z = 0 and a rotation about z.
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::app {

/// Collects the planar poses of one run with their times; a pose that is not finite (a step
/// without truth) is left out, so the file has only poses that were known.
class TumTrack {
 public:
  void add(double time, const robot::Pose& pose) {
    if (!std::isfinite(time) || !pose.allFinite()) return;
    times_.push_back(time);
    poses_.push_back(pose);
  }
  std::size_t size() const { return times_.size(); }

  /// Writes the file whole or not at all (OutputFile). Throws InvalidArgument naming `flag` when
  /// there is nothing to write or two poses share a time (TUM needs increasing times).
  void write(const std::filesystem::path& file, std::string_view flag) const {
    require(!times_.empty(), "{} {}: no pose with a known position and heading to write", flag,
            file.string());
    for (std::size_t k = 1; k < times_.size(); ++k)
      require(times_[k] > times_[k - 1],
              "{} {}: pose {} has time {} s, not after the previous pose's {} s (TUM needs "
              "increasing times)",
              flag, file.string(), k + 1, times_[k], times_[k - 1]);
    OutputFile out(file, OutputFile::Mode::kReplace, std::string(flag));
    out.stream() << robot::format_tum(robot::Trajectory::from_se2(times_, poses_));
    out.commit();
  }

 private:
  std::vector<double> times_;
  std::vector<robot::Pose> poses_;
};

/// The check of --trajectory and --truth-trajectory, before any run: a name, in a folder that
/// exists (a long run must not end in "cannot write" for a typing error).
inline CLI::Validator tum_file_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty()) return "expected a file name, got an empty one";
        const std::filesystem::path folder = std::filesystem::path(text).parent_path();
        std::error_code ec;
        if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
          return "expected a file in an existing folder, got '" + text + "' (no folder '" +
                 folder.string() + "')";
        return {};
      },
      "FILE");
}

}  // namespace implicit::app
