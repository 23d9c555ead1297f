#pragma once
// --trajectory and --truth-trajectory of mcl and slam: a run's estimate (or the reference it is
// scored against) as a TUM file (t x y z qx qy qz qw, docs/formats.md), the input of
// `implicit eval` and of evo. Planar poses embed as z = 0 and a rotation about z. (The flags' check
// before any run is the command line's: apps/tum_output.hpp.)
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::experiments {

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

}  // namespace implicit::experiments
