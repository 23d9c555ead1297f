#pragma once
// EKF-SLAM's linear algebra, independent of the vehicle and sensor models.
//
// The state is s = (pose (3), m_1 (2), ..., m_N (2)) with covariance P (3+2N square). The models
// enter only through their Jacobians, so the same core runs the Ute/range-bearing EKF-SLAM and,
// in the tests, a linear-Gaussian problem where it must equal the exact (Kalman) posterior.
//
//   EkfSlamCore ekf(x0, Mat<3>::Zero());
//   ekf.predict(f(x), J_f_x, Sigma1);                 // pose moves, landmarks do not
//   int k = ekf.augment(g(x, z), J_g_x, J_g_z * Sigma2 * J_g_z^T);  // first sighting
//   ekf.update(k, wrap(z - h(x, m_k)), J_h_x, J_h_m, Sigma2);       // later sightings
//
// Updates use the Joseph form P <- (I - K H) P (I - K H)^T + K R K^T, evaluated in O(n^2) with the
// sparsity of H (5 non-zero columns) as one rank-4 update of the lower triangle, mirrored so P
// stays exactly symmetric; S is factorised by Cholesky (no inverse).
// Mistake to avoid: passing the residual h - z instead of the innovation z - h (sign).

#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit::slam {

using Mat23 = Eigen::Matrix<double, 2, 3>;

class EkfSlamCore {
 public:
  EkfSlamCore(const Vec<3>& pose, const Mat<3>& pose_covariance);

  int landmark_count() const { return static_cast<int>((mean_.size() - 3) / 2); }
  const Eigen::VectorXd& mean() const { return mean_; }
  const Eigen::MatrixXd& covariance() const { return cov_; }
  Vec<3> pose() const { return mean_.head<3>(); }
  Mat<3> pose_covariance() const { return cov_.topLeftCorner<3, 3>(); }
  Vec<2> landmark(int k) const { return mean_.segment<2>(3 + 2 * k); }
  Mat<2> landmark_covariance(int k) const { return cov_.block<2, 2>(3 + 2 * k, 3 + 2 * k); }

  /// Pose prediction: pose <- new_pose, P_pp <- F P_pp F^T + Q, P_pm <- F P_pm.
  void predict(const Vec<3>& new_pose, const Mat<3>& F, const Mat<3>& Q);

  /// Innovation covariance S = H P H^T + R for landmark k, H = [Hx at pose, Hm at k].
  Mat<2> innovation_covariance(int k, const Mat23& Hx, const Mat<2>& Hm, const Mat<2>& R) const;

  /// Kalman update with innovation nu = z - h. Returns false (and changes nothing) when S is not
  /// positive definite or the inputs are not finite.
  bool update(int k, const Vec<2>& innovation, const Mat23& Hx, const Mat<2>& Hm, const Mat<2>& R);

  /// Appends landmark m = g(pose, z) with cross-covariance Gx P_p. and own covariance
  /// Gx P_pp Gx^T + GzRGz; returns its index.
  int augment(const Vec<2>& m, const Mat23& Gx, const Mat<2>& GzRGz);

 private:
  void mirror_lower_to_upper();

  Eigen::VectorXd mean_;
  Eigen::MatrixXd cov_;
};

}  // namespace implicit::slam
