#pragma once
// Running a SLAM estimator over a data set and scoring it (spec §4).
//
//   slam::SlamRun run = slam::run_filter(data, options);
//   slam::SlamMetrics m = slam::evaluate(data, run);
//   // m.error_percent (paper metric), m.map_shape_m (landmark RMSE after rigid alignment), ...
//
// Metrics (positions p = (x, y) of the laser; the estimate at step n is the weighted particle
// mean after the weights of step n, before resampling):
//   error_percent         100 sqrt(sum |p_hat - p|^2) / sqrt(sum |p|^2), the paper's metric;
//   rmse_pose_m           sqrt(mean |p_hat - p|^2); rmse_heading_rad with wrapped differences;
//   rmse_map_m            sqrt(mean |m_hat - m|^2) over the landmarks in the estimated map;
//   map_shape_m           the same after the best rigid (rotation + translation) alignment of the
//                         estimated map onto the true one (Umeyama/Horn, no scale); both, and
//                         map_error_percent, are NaN when the data set has no true map (e.g.
//                         Victoria Park): nothing to compare with, not an error of 0;
//   error_aligned_percent err% of the path after applying that same map alignment (when the
//                         data set has no true map, e.g. GPS only: the path is aligned to itself);
//   nees_mean             mean over steps of e^T P^-1 e, e = (p_hat - p, wrap(b_hat - b)).
// Which estimated landmark corresponds to which true one: the known ids when the filter used
// known association, otherwise the nearest true landmark to each estimated one.

#include <cstddef>
#include <functional>
#include <vector>

#include "implicit/slam/dataset.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {

/// p -> R p + t with R a rotation.
struct RigidTransform2 {
  Mat<2> rotation = Mat<2>::Identity();
  Vec<2> translation = Vec<2>::Zero();
  Vec<2> apply(const Vec<2>& p) const { return rotation * p + translation; }
  double angle() const;
};

/// Least-squares rigid alignment: minimises sum_i |R from_i + t - to_i|^2 (Umeyama 1991 without
/// scale). Needs at least two distinct points; throws InvalidArgument on size mismatch.
RigidTransform2 align_rigid(const std::vector<Vec<2>>& from, const std::vector<Vec<2>>& to);

struct SlamRun {
  std::vector<Pose> path;        ///< estimate per step 0..N
  std::vector<Mat<3>> path_cov;  ///< its covariance per step
  MapEstimate map;               ///< final map
  SlamStats stats;
  double wall_seconds = 0.0;
  std::size_t map_bytes = 0;  ///< landmark storage at the end
};

/// Runs the estimator from the data set's initial pose over every step. With `known_map` the
/// filter starts with the true landmarks (localisation). `on_step`, if set, is called after each
/// step (progress within a long run).
SlamRun run_filter(const SlamDataset& data, const SlamOptions& options, bool known_map = false,
                   const std::function<void()>& on_step = {});

struct SlamMetrics {
  double error_percent = 0.0;
  double error_aligned_percent = 0.0;
  double rmse_pose_m = 0.0;
  double rmse_pose_aligned_m = 0.0;  ///< position RMSE after the alignment (as error_aligned)
  double rmse_heading_rad = 0.0;
  double rmse_map_m = 0.0;         ///< NaN without a true map
  double map_shape_m = 0.0;        ///< NaN without a true map
  double map_error_percent = 0.0;  ///< 100 |Theta_hat - Theta|_F / |Theta|_F; NaN without a map
  double alignment_angle_rad = 0.0;
  double nees_mean = 0.0;  ///< over steps with an SPD covariance
  std::size_t nees_steps = 0;
  std::size_t landmarks = 0;     ///< in the estimated map
  std::size_t scored_steps = 0;  ///< steps with truth; 0 makes the pose metrics NaN
  std::vector<double> nees;      ///< per step (NaN where undefined)
};

SlamMetrics evaluate(const SlamDataset& data, const SlamRun& run);

/// Quantile of the chi-square distribution with k degrees of freedom (Wilson-Hilferty; relative
/// error below 1e-3 for k >= 30, enough for consistency bands).
double chi_square_quantile(double p, double k);

}  // namespace implicit::slam
