// Fuzz target: the trajectory readers (src/robot/trajectory_io.cpp) and the scoring that reads
// their output, as `implicit eval` runs them.
//
// An input is three files separated by lines "%%": a TUM trajectory, a KITTI trajectory and a
// relations file. Each reader must accept its file or throw ParseError; a trajectory that is
// accepted is scored against itself (association, SE(3) alignment, APE, RPE) and the relations
// against the TUM one, which may throw InvalidArgument (no pairs, degenerate positions) and
// nothing else. Another exception, a crash or a sanitizer report is a finding.

#include <cstdint>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/trajectory_metrics.hpp"
#include "scratch.hpp"

namespace {

void fuzz_trajectory_score(const implicit::robot::Trajectory& t) {
  using namespace implicit::robot;
  try {
    const PosePairs pairs = associate(t, t);
    const TrajectoryErrors ape =
        absolute_pose_error(pairs, align_umeyama(pairs, AlignmentKind::kSe3));
    error_statistics(ape.translation, {.resamples = 10});
    relative_pose_error(pairs, {}, {.delta = 1, .unit = DeltaUnit::kMetres});
  } catch (const implicit::InvalidArgument&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace implicit::robot;
  const auto parts = implicit::fuzz::split_files(implicit::fuzz::as_text(data, size), 3);
  Trajectory tum;
  try {
    tum = parse_tum(parts[0], "fuzz.tum");
    fuzz_trajectory_score(tum);
  } catch (const implicit::ParseError&) {
  }
  try {
    fuzz_trajectory_score(parse_kitti(parts[1], "fuzz.kitti"));
  } catch (const implicit::ParseError&) {
  }
  try {
    const std::vector<Relation> relations = parse_relations(parts[2], "fuzz.relations");
    if (!tum.empty()) relation_errors(tum, relations);
  } catch (const implicit::ParseError&) {
  } catch (const implicit::InvalidArgument&) {
  }
  return 0;
}
