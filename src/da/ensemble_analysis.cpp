// The analyses of the two Kalman-type baselines (filters.hpp): perturbed-observation EnKF and
// the symmetric square-root ETKF (Hunt, Kostelich and Szunyogh's form in ensemble space).
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "implicit/da/filters.hpp"

namespace implicit::da {

void enkf_perturbed_analysis(Eigen::MatrixXd& E, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                             const Eigen::MatrixXd& lr, const Eigen::VectorXd& y,
                             const Eigen::MatrixXd& normals) {
  const double n1 = static_cast<double>(E.cols() - 1);
  const Eigen::VectorXd mean = E.rowwise().mean();
  const Eigen::MatrixXd A = E.colwise() - mean;
  const Eigen::MatrixXd S = H * A;
  // K d = A S^T ((S S^T + (N-1) R))^-1 d: the 1/(N-1) of both covariances cancels.
  const Eigen::LLT<Eigen::MatrixXd> innovation((S * S.transpose() + n1 * R).eval());
  Eigen::MatrixXd d = lr * normals;
  d.colwise() += y;
  d.noalias() -= H * E;
  E.noalias() += A * (S.transpose() * innovation.solve(d));
}

void etkf_analysis(Eigen::MatrixXd& E, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                   const Eigen::VectorXd& y) {
  const double n1 = static_cast<double>(E.cols() - 1);
  const Eigen::VectorXd mean = E.rowwise().mean();
  const Eigen::MatrixXd A = E.colwise() - mean;
  const Eigen::MatrixXd Y = H * A;
  const Eigen::MatrixXd r_inv_y = R.llt().solve(Y);
  // In ensemble space: Pa~ = ((N-1) I + Y^T R^-1 Y)^-1 (symmetric, eigenvalues >= N-1 > 0),
  // mean weights w = Pa~ Y^T R^-1 (y - H mean), anomaly transform W = ((N-1) Pa~)^{1/2}.
  Eigen::MatrixXd c = Y.transpose() * r_inv_y;
  c.diagonal().array() += n1;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
  const Eigen::MatrixXd& v = eig.eigenvectors();
  const Eigen::ArrayXd lambda = eig.eigenvalues().array();
  const Eigen::VectorXd innovation = y - H * mean;
  const Eigen::VectorXd w = v * (lambda.inverse().matrix().asDiagonal() *
                                 (v.transpose() * (r_inv_y.transpose() * innovation)));
  Eigen::MatrixXd transform = v * (n1 / lambda).sqrt().matrix().asDiagonal() * v.transpose();
  transform.colwise() += w;
  E = A * transform;
  E.colwise() += mean;
}

}  // namespace implicit::da
