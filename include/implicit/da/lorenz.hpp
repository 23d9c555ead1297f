#pragma once
// The Lorenz models of data assimilation (docs/specification.md, "Data assimilation"): their
// tendencies, the classical RK4 step, and the derivative of the k-step map by the tangent linear
// of RK4 (each stage differentiated, so the derivative is exact for the discrete map, not an
// approximation of the flow's).
//
//   implicit::da::Lorenz63 l63;                          // sigma 10, rho 28, beta 8/3
//   Eigen::Vector3d x(1.509, -1.531, 25.46);
//   Eigen::Matrix3d J;
//   l63.steps(x, 0.01, 25, &J);                          // x <- M(x), J = dM/dx
//
//   implicit::da::Lorenz96 l96(40, 8.0);
//   implicit::da::Lorenz96::Workspace w(40);             // once, reused every step
//   l96.steps(x96, 0.05, 1, w);                          // no allocation
//
// Lorenz-63 is fixed size (3). Lorenz-96 has any dimension n >= 4 (its advection couples
// x[i-2], x[i-1], x[i+1]) and works in a caller-owned Workspace, so a filter keeps one per
// member and a forecast allocates nothing.

#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit::da {

/// dx/dt = (sigma (y - x), x (rho - z) - y, x y - beta z).
struct Lorenz63 {
  double sigma = 10.0;
  double rho = 28.0;
  double beta = 8.0 / 3.0;

  Vec<3> tendency(const Vec<3>& x) const {
    return {sigma * (x(1) - x(0)), x(0) * (rho - x(2)) - x(1), x(0) * x(1) - beta * x(2)};
  }
  /// d tendency / dx at x.
  Mat<3> tendency_jacobian(const Vec<3>& x) const {
    Mat<3> j;
    j << -sigma, sigma, 0.0, rho - x(2), -1.0, -x(0), x(1), x(0), -beta;
    return j;
  }
  /// One classical RK4 step of length dt.
  void step(Vec<3>& x, double dt) const;
  /// k RK4 steps; with `jacobian`, also the derivative of the k-step map at the start.
  void steps(Vec<3>& x, double dt, int k, Mat<3>* jacobian = nullptr) const;
};

/// dx_i/dt = (x_{i+1} - x_{i-2}) x_{i-1} - x_i + F, indices cyclic.
class Lorenz96 {
 public:
  /// Preallocated stage vectors (and tangent-linear matrices when a Jacobian is asked for).
  struct Workspace {
    Eigen::VectorXd k1, k2, k3, k4, stage;
    Eigen::MatrixXd t1, t2, t3, t4, tstage;  ///< sized on the first Jacobian request
    explicit Workspace(int n = 0) { resize(n); }
    void resize(int n);
  };

  /// Throws InvalidArgument for n < 4 or a non-finite forcing.
  Lorenz96(int n, double forcing);

  int dim() const { return n_; }
  double forcing() const { return forcing_; }

  /// out = tendency at x (out must not alias x).
  void tendency(const Eigen::VectorXd& x, Eigen::VectorXd& out) const;
  /// out = (d tendency / dx at x) v, for every column of v (out must not alias v).
  void apply_tendency_jacobian(const Eigen::VectorXd& x, const Eigen::MatrixXd& v,
                               Eigen::MatrixXd& out) const;
  /// One classical RK4 step of length dt, in w's storage (x must have size dim()).
  void step(Eigen::VectorXd& x, double dt, Workspace& w) const;
  /// k RK4 steps; with `jacobian`, also the derivative of the k-step map at the start.
  void steps(Eigen::VectorXd& x, double dt, int k, Workspace& w,
             Eigen::MatrixXd* jacobian = nullptr) const;

 private:
  int n_;
  double forcing_;
};

}  // namespace implicit::da
