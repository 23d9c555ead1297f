#include "implicit/da/model.hpp"

#include <cmath>
#include <utility>

#include "implicit/core/error.hpp"

namespace implicit::da {

void Model::forecast_jacobian(Eigen::VectorXd&, Eigen::MatrixXd&, ForecastWorkspace&) const {
  throw InvalidArgument(
      fmt::format("model {}: has no derivative of its forecast (needed by the smoother)", name()));
}

LinearModel::LinearModel(Eigen::MatrixXd a) : a_(std::move(a)) {
  require(a_.rows() == a_.cols() && a_.rows() >= 1,
          "linear model: expected a square matrix A, got {} x {}", a_.rows(), a_.cols());
  require(a_.allFinite(), "linear model: expected a finite matrix A, got a NaN or inf entry");
}

void LinearModel::forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const {
  // x = A x would alias; the workspace's stage vector holds the product.
  w.l96.stage.noalias() = a_ * x;
  x = w.l96.stage;
}

void LinearModel::forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                                    ForecastWorkspace& w) const {
  forecast(x, w);
  jacobian = a_;
}

Lorenz63Model::Lorenz63Model(const Lorenz63& l, double dt, int substeps)
    : l_(l), dt_(dt), substeps_(substeps) {
  require(std::isfinite(dt) && dt > 0.0, "Lorenz-63: expected a positive step dt, got {}", dt);
  require(substeps >= 1, "Lorenz-63: expected at least 1 RK4 step per observation, got {}",
          substeps);
  require(std::isfinite(l.sigma) && std::isfinite(l.rho) && std::isfinite(l.beta),
          "Lorenz-63: expected finite sigma, rho, beta, got {}, {}, {}", l.sigma, l.rho, l.beta);
}

void Lorenz63Model::forecast(Eigen::VectorXd& x, ForecastWorkspace&) const {
  Vec<3> v = x;
  l_.steps(v, dt_, substeps_);
  x = v;
}

void Lorenz63Model::forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                                      ForecastWorkspace&) const {
  Vec<3> v = x;
  Mat<3> j;
  l_.steps(v, dt_, substeps_, &j);
  x = v;
  jacobian = j;
}

Lorenz96Model::Lorenz96Model(const Lorenz96& l, double dt, int substeps)
    : l_(l), dt_(dt), substeps_(substeps) {
  require(std::isfinite(dt) && dt > 0.0, "Lorenz-96: expected a positive step dt, got {}", dt);
  require(substeps >= 1, "Lorenz-96: expected at least 1 RK4 step per observation, got {}",
          substeps);
}

void Lorenz96Model::forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const {
  l_.steps(x, dt_, substeps_, w.l96);
}

void Lorenz96Model::forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                                      ForecastWorkspace& w) const {
  l_.steps(x, dt_, substeps_, w.l96, &jacobian);
}

void require_spd(const Eigen::MatrixXd& m, int size, const char* what) {
  require(m.rows() == size && m.cols() == size, "{}: expected a {} x {} matrix, got {} x {}", what,
          size, size, m.rows(), m.cols());
  require(m.allFinite(), "{}: expected finite entries, got a NaN or inf", what);
  const double scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  require((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale,
          "{}: expected a symmetric matrix", what);
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  require(llt.info() == Eigen::Success && llt.matrixLLT().diagonal().minCoeff() > 0.0,
          "{}: expected a positive-definite matrix (its Cholesky factorisation failed)", what);
}

void Problem::validate() const {
  require(model != nullptr, "data assimilation problem: expected a model, got none");
  const int n = model->dim();
  require(H.rows() >= 1 && H.cols() == n,
          "observation operator H: expected {} columns (the state dimension) and at least one "
          "row, got {} x {}",
          n, H.rows(), H.cols());
  require(H.allFinite(), "observation operator H: expected finite entries, got a NaN or inf");
  require_spd(R, static_cast<int>(H.rows()), "observation noise R");
  if (stochastic()) require_spd(Q, n, "model noise Q");
  require(steps_per_observation >= 1,
          "data assimilation problem: expected at least 1 model interval per observation, got {}",
          steps_per_observation);
}

void require_observation(const Problem& p, const Eigen::VectorXd& y, long cycle) {
  require(y.size() == p.obs_dim(), "observation {}: expected {} values (the rows of H), got {}",
          cycle, p.obs_dim(), y.size());
  require(y.allFinite(), "observation {}: expected finite values, got a NaN or inf", cycle);
}

}  // namespace implicit::da
