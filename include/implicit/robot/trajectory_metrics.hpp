#pragma once
// Scoring an estimated trajectory: association by time, alignment, APE, RPE and the relation
// metric, with the definitions of the evo package (and of Sturm et al. 2012 and Kümmerle et al.
// 2009) so that numbers can be compared with theirs.
//
//   auto pairs = robot::associate(ref, est, {.max_diff = 0.01});
//   auto align = robot::align_umeyama(pairs, robot::AlignmentKind::kSe3);
//   robot::TrajectoryErrors ape = robot::absolute_pose_error(pairs, align);
//   robot::TrajectoryErrors rpe = robot::relative_pose_error(pairs, align, {.delta = 1});
//   robot::ErrorStatistics s = robot::error_statistics(ape.translation, {.seed = 7});
//   robot::RelationErrors rel = robot::relation_errors(est, relations, {.max_diff = 0.01});
//
// Error of a pose pair: E = ref^-1 est (APE) and E = ref_rel^-1 est_rel with rel = pose_i^-1
// pose_j (RPE); E's inverse has the same translation norm, angle and |E - I|_F, so the order
// does not change a number. Each E gives a translation error |t_E| [m], a rotation angle of R_E
// [deg] and a "full" error |E - I|_F (4x4, unitless, as evo's full transformation).
//
// Statistics are evo's: mean, median, RMSE, max, min and the population standard deviation (n in
// the denominator), with percentile bootstrap intervals of the mean and the RMSE.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "implicit/robot/trajectory.hpp"

namespace implicit::robot {

struct TimeAssociationOptions {
  double max_diff = 0.01;  ///< [s] largest |t_ref - (t_est + offset)| of a pair
  double offset = 0.0;     ///< [s] added to the estimate's times
};

/// Poses of the reference and the estimate at matching times, in time order.
struct PosePairs {
  std::vector<double> times;  ///< the reference's times
  std::vector<Pose3> ref, est;
  std::vector<std::size_t> ref_index, est_index;  ///< where each pair came from
  std::size_t size() const { return times.size(); }
};

/// For each reference pose, the estimated pose nearest in time (after the offset) if within
/// max_diff. Each estimated pose is used at most once: when two reference poses find the same
/// one, the closer keeps it (evo can pair one estimate twice). Throws InvalidArgument when an
/// option is not finite or max_diff < 0, or when no pair is found (naming both trajectories'
/// time ranges).
PosePairs associate(const Trajectory& ref, const Trajectory& est,
                    const TimeAssociationOptions& options = {});

enum class AlignmentKind { kNone, kSe2, kSe3, kSim3 };
const char* to_string(AlignmentKind kind);
/// "none", "se2", "se3", "sim3"; throws InvalidArgument otherwise.
AlignmentKind alignment_kind_from_string(const std::string& text);

/// x -> scale * rotation * x + translation, applied to the estimate.
struct Alignment {
  AlignmentKind kind = AlignmentKind::kNone;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec<3> translation = Vec<3>::Zero();
  double scale = 1.0;
  Pose3 apply(const Pose3& p) const;
  double rotation_angle() const;  ///< [rad]
};

/// Least-squares alignment of the estimated positions onto the reference ones (Umeyama 1991):
/// minimises sum_i |ref_i - (s R est_i + t)|^2 over R, t (and s for Sim(3)). kSe2 rotates about z
/// only (the z offset is still fitted). Throws InvalidArgument when the positions do not fix the
/// transform: fewer than 2 pairs (SE(2)) or 3 (SE(3), Sim(3)), all estimated positions equal, or
/// (SE(3), Sim(3)) all on one line.
Alignment align_umeyama(const std::vector<Vec<3>>& est, const std::vector<Vec<3>>& ref,
                        AlignmentKind kind);
Alignment align_umeyama(const PosePairs& pairs, AlignmentKind kind);

/// Per-pair errors: translation [m], rotation angle [deg], |E - I|_F.
struct TrajectoryErrors {
  std::vector<double> translation, rotation_deg, full;
  std::vector<std::size_t> first, second;  ///< pair indices the errors belong to (RPE: i, j)
};

TrajectoryErrors absolute_pose_error(const PosePairs& pairs, const Alignment& alignment = {});

enum class DeltaUnit { kFrames, kMetres };
const char* to_string(DeltaUnit unit);

struct RpeOptions {
  double delta = 1.0;  ///< frames (a positive integer) or metres (> 0) of the reference's path
  DeltaUnit unit = DeltaUnit::kFrames;
  /// false (evo's default): pairs (i, j), (j, k), ... that do not overlap; true: one pair per i.
  bool all_pairs = false;
};

/// Relative pose error over pairs (i, j) of associated poses: j = i + delta (frames), or the first
/// j whose path length along the reference from i reaches delta (metres). The alignment matters
/// only through its scale. Throws InvalidArgument for a bad delta or when no pair fits.
TrajectoryErrors relative_pose_error(const PosePairs& pairs, const Alignment& alignment,
                                     const RpeOptions& options);

struct StatisticsOptions {
  std::uint64_t seed = 1;
  int resamples = 1000;  ///< bootstrap resamples; 0: no intervals (NaN)
  double level = 0.95;   ///< of the intervals
};

struct ErrorStatistics {
  std::size_t count = 0;
  double mean = 0, median = 0, rmse = 0, max = 0, min = 0, std = 0;
  double mean_lo = 0, mean_hi = 0, rmse_lo = 0, rmse_hi = 0;  ///< bootstrap intervals
};

/// Throws InvalidArgument on no values, a non-finite value, or bad options. Deterministic for a
/// seed (draws from core/rng.hpp, purpose kUser + 40).
ErrorStatistics error_statistics(const std::vector<double>& values,
                                 const StatisticsOptions& options = {});

/// Kümmerle et al. 2009: for each relation (t1, t2, delta*), the estimated motion
/// delta = est(t1)^-1 est(t2) and its error E = delta*^-1 delta.
struct RelationErrors {
  std::vector<double> translation, rotation_deg;
  std::vector<std::size_t> used;  ///< index of the relation of each error
  std::size_t skipped = 0;        ///< relations without an estimated pose at t1 or t2
  double translation_mean = 0, translation_sq_mean = 0;    ///< [m], [m^2]
  double rotation_mean_deg = 0, rotation_sq_mean_deg = 0;  ///< [deg], [deg^2]
};

/// Estimated poses are looked up by time as in associate (nearest within max_diff, after the
/// offset). Throws InvalidArgument when no relation finds both of its poses.
RelationErrors relation_errors(const Trajectory& est, const std::vector<Relation>& relations,
                               const TimeAssociationOptions& options = {});

}  // namespace implicit::robot
