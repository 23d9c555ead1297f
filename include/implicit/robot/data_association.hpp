#pragma once
// Maximum-likelihood data association with a chi-square gate, and the clutter density of a
// detection that matches nothing.
//
// A detection z is compared with candidates i = 0..n-1 (known landmarks, or a SLAM particle's
// landmark estimates), each giving an innovation e_i = h_i - z (angles wrapped) and its covariance
// S_i. The chosen candidate minimises the negative log likelihood
//
//   cost_i = d_i^2 + log det S_i,   d_i^2 = e_i^T S_i^{-1} e_i,
//
// among those inside the gate d_i^2 <= gate (chi-square, 2 dof: 9.21 = 99 %). No candidate inside
// the gate: the result is kNoMatch ("clutter" in localization, "new landmark" in SLAM).
//
//   auto a = associate_max_likelihood(map.size(), [&](int i, Measurement& e, Mat2& s) {
//     e = sensor.residual(sensor.predict(x, map.position(i)), z);
//     s = sensor.noise_covariance();
//     return true;                          // false: candidate not visible, skip it
//   }, 9.21);
//   if (a.matched()) ... a.index ...
//
// A dropped detection must still contribute a likelihood, otherwise particles that drop different
// detections get incomparable weights. clutter_log_density(gate, Sigma2) = log N(e; 0, Sigma2) on
// the gate boundary e^T Sigma2^{-1} e = gate, so the per-detection likelihood is max(N(e; 0,
// Sigma2), p0).
//
// Common mistakes: comparing d^2 alone when the S_i differ between candidates (the log det S term
// matters), and forgetting to wrap the bearing innovation.

#include <cmath>
#include <limits>
#include <span>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// chi-square quantile with 2 degrees of freedom at 99 %: -2 log(0.01).
inline constexpr double kChiSquare2Dof99 = 9.21034037197618;

struct Association {
  static constexpr int kNoMatch = -1;
  int index = kNoMatch;  ///< chosen candidate, or kNoMatch (clutter / new landmark)
  double mahalanobis2 = std::numeric_limits<double>::infinity();  ///< d^2 of the chosen candidate
  double log_det_innovation = 0.0;  ///< log det S of the chosen candidate
  bool matched() const { return index != kNoMatch; }
};

/// d^2 = e^T S^{-1} e and log det S of a 2x2 innovation covariance (closed form, no inverse
/// formed). Returns false when S is not positive definite.
inline bool innovation_statistics(const Measurement& e, const Mat2& s, double& mahalanobis2,
                                  double& log_det) {
  const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
  if (!(det > 0.0) || !(s(0, 0) > 0.0)) return false;
  // S^{-1} e by Cramer's rule: exact for 2x2 and cheaper than a factorisation.
  const double a = (s(1, 1) * e(0) - s(0, 1) * e(1)) / det;
  const double b = (s(0, 0) * e(1) - s(1, 0) * e(0)) / det;
  mahalanobis2 = e(0) * a + e(1) * b;
  log_det = std::log(det);
  return std::isfinite(mahalanobis2);
}

/// Maximum likelihood over n candidates. `candidate(i, e, S)` fills the innovation and its
/// covariance of candidate i and returns false to skip it. Never throws; non-SPD S are skipped.
template <typename CandidateFn>
Association associate_max_likelihood(int n, CandidateFn&& candidate, double gate) {
  Association best;
  double best_cost = std::numeric_limits<double>::infinity();
  Measurement e;
  Mat2 s;
  for (int i = 0; i < n; ++i) {
    if (!candidate(i, e, s)) continue;
    double d2 = 0.0, log_det = 0.0;
    if (!innovation_statistics(e, s, d2, log_det) || d2 > gate) continue;
    const double cost = d2 + log_det;
    if (cost < best_cost) {
      best_cost = cost;
      best.index = i;
      best.mahalanobis2 = d2;
      best.log_det_innovation = log_det;
    }
  }
  return best;
}

/// Candidates given by their means and covariances (SLAM landmark estimates), seen from a pose
/// with covariance pose_cov (zero for a sampled pose): S_i = Hx P Hx^T + Hm C_i Hm^T + Sigma2.
/// `covariances` may be empty (known landmarks). Candidates closer than min_range are skipped.
template <typename Sensor>
Association associate_landmark(const Sensor& sensor, const Pose& pose, const Mat3& pose_cov,
                               std::span<const Landmark> means, std::span<const Mat2> covariances,
                               const Measurement& z, double gate, double min_range = 1e-6) {
  const Mat2& noise = sensor.noise_covariance();
  return associate_max_likelihood(
      static_cast<int>(means.size()),
      [&](int i, Measurement& e, Mat2& s) {
        const Landmark& m = means[static_cast<std::size_t>(i)];
        if ((m - pose.head<2>()).norm() < min_range) return false;
        e = sensor.residual(sensor.predict(pose, m), z);
        const Mat23 hx = sensor.jacobian_pose(pose, m);
        s = hx * pose_cov * hx.transpose() + noise;
        if (!covariances.empty()) {
          const Mat2 hm = -hx.leftCols<2>();
          s += hm * covariances[static_cast<std::size_t>(i)] * hm.transpose();
        }
        return true;
      },
      gate);
}

/// log p0: the Gaussian N(0, Sigma2) log density on the gate boundary d^2 = gate.
inline double clutter_log_density(double gate, const Mat2& sigma2) {
  const double det = sigma2(0, 0) * sigma2(1, 1) - sigma2(0, 1) * sigma2(1, 0);
  return -0.5 * gate - gaussian_log_normaliser(2, 0.0) - 0.5 * std::log(det);
}

}  // namespace implicit::robot
