// EKF-SLAM linear algebra: prediction, Joseph-form update, augmentation (O(n^2) each).
#include <algorithm>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/slam/ekf_slam.hpp"

namespace implicit::slam {

EkfSlamCore::EkfSlamCore(const Vec<3>& pose, const Mat<3>& pose_covariance)
    : mean_(pose), cov_(pose_covariance) {
  require(pose.allFinite(), "EKF-SLAM: expected a finite initial pose");
  require(pose_covariance.allFinite() &&
              (pose_covariance - pose_covariance.transpose()).cwiseAbs().maxCoeff() <=
                  1e-12 * (1.0 + pose_covariance.cwiseAbs().maxCoeff()),
          "EKF-SLAM: expected a finite symmetric initial pose covariance");
}

void EkfSlamCore::predict(const Vec<3>& new_pose, const Mat<3>& F, const Mat<3>& Q) {
  const Eigen::Index n = mean_.size();
  mean_.head<3>() = new_pose;
  const Mat<3> ppp = F * cov_.topLeftCorner<3, 3>() * F.transpose() + Q;
  cov_.topLeftCorner<3, 3>() = 0.5 * (ppp + ppp.transpose());
  if (n > 3) {
    const Eigen::MatrixXd pm = F * cov_.topRightCorner(3, n - 3);
    cov_.topRightCorner(3, n - 3) = pm;
    cov_.bottomLeftCorner(n - 3, 3) = pm.transpose();
  }
}

Mat<2> EkfSlamCore::innovation_covariance(int k, const Mat23& Hx, const Mat<2>& Hm,
                                          const Mat<2>& R) const {
  const Eigen::Index i = 3 + 2 * k;
  const Mat<3> ppp = cov_.topLeftCorner<3, 3>();
  const Eigen::Matrix<double, 3, 2> ppm = cov_.block<3, 2>(0, i);
  const Mat<2> pmm = cov_.block<2, 2>(i, i);
  const Mat<2> cross = Hx * ppm * Hm.transpose();
  Mat<2> s = Hx * ppp * Hx.transpose() + cross + cross.transpose() + Hm * pmm * Hm.transpose() + R;
  return 0.5 * (s + s.transpose());
}

bool EkfSlamCore::update(int k, const Vec<2>& innovation, const Mat23& Hx, const Mat<2>& Hm,
                         const Mat<2>& R) {
  require(k >= 0 && k < landmark_count(),
          "EKF-SLAM update: expected a landmark index below {}, got {}", landmark_count(), k);
  if (!innovation.allFinite() || !Hx.allFinite() || !Hm.allFinite()) return false;
  const Eigen::Index i = 3 + 2 * k;
  // PHt = P H^T (n x 2), using the 5 non-zero columns of H.
  const Eigen::MatrixXd pht =
      cov_.leftCols<3>() * Hx.transpose() + cov_.middleCols<2>(i) * Hm.transpose();
  Mat<2> s = Hx * pht.topRows<3>() + Hm * pht.middleRows<2>(i) + R;
  s = 0.5 * (s + s.transpose());
  const Eigen::LLT<Mat<2>> llt(s);
  if (llt.info() != Eigen::Success) return false;
  // K = PHt S^{-1}  <=>  K^T = S^{-1} PHt^T.
  const Eigen::MatrixX2d gain = llt.solve(pht.transpose()).transpose();
  mean_.noalias() += gain * innovation;
  // Joseph form (I - K H) P (I - K H)^T + K R K^T = P - K PHt^T - PHt K^T + K S K^T
  //   = P - PHt K^T + K W^T  with  W = K S - PHt
  // (W is the round-off residual of the gain; keeping it keeps the Joseph form's robustness).
  // One rank-4 update of the lower triangle, then a mirror: two half passes over P instead of
  // the six full passes of the textbook product form, which dominate at hundreds of landmarks.
  const Eigen::Index n = cov_.rows();
  Eigen::MatrixX4d u(n, 4), v(n, 4);
  u << -pht, gain;
  v << gain, gain * s - pht;
  cov_.triangularView<Eigen::Lower>() += u * v.transpose();
  mirror_lower_to_upper();
  return true;
}

void EkfSlamCore::mirror_lower_to_upper() {
  // Tile by tile, so that the transposed reads stay in cache.
  constexpr Eigen::Index kTile = 64;
  const Eigen::Index n = cov_.rows();
  for (Eigen::Index j0 = 0; j0 < n; j0 += kTile) {
    const Eigen::Index bj = std::min(kTile, n - j0);
    for (Eigen::Index j = j0; j < j0 + bj; ++j)  // the diagonal tile
      for (Eigen::Index i = j + 1; i < j0 + bj; ++i) cov_(j, i) = cov_(i, j);
    for (Eigen::Index i0 = j0 + bj; i0 < n; i0 += kTile) {
      const Eigen::Index bi = std::min(kTile, n - i0);
      cov_.block(j0, i0, bj, bi) = cov_.block(i0, j0, bi, bj).transpose();
    }
  }
}

int EkfSlamCore::augment(const Vec<2>& m, const Mat23& Gx, const Mat<2>& GzRGz) {
  const Eigen::Index n = mean_.size();
  mean_.conservativeResize(n + 2);
  mean_.tail<2>() = m;
  const Eigen::MatrixXd cross = Gx * cov_.topRows<3>();  // 2 x n
  Mat<2> pmm = Gx * cov_.topLeftCorner<3, 3>() * Gx.transpose() + GzRGz;
  cov_.conservativeResize(n + 2, n + 2);
  cov_.block(n, 0, 2, n) = cross;
  cov_.block(0, n, n, 2) = cross.transpose();
  cov_.block<2, 2>(n, n) = 0.5 * (pmm + pmm.transpose());
  return landmark_count() - 1;
}

}  // namespace implicit::slam
