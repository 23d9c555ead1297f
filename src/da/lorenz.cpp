#include "implicit/da/lorenz.hpp"

#include <cmath>

#include "implicit/core/error.hpp"

namespace implicit::da {

void Lorenz63::step(Vec<3>& x, double dt) const {
  const Vec<3> k1 = tendency(x);
  const Vec<3> k2 = tendency(x + 0.5 * dt * k1);
  const Vec<3> k3 = tendency(x + 0.5 * dt * k2);
  const Vec<3> k4 = tendency(x + dt * k3);
  x += (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

void Lorenz63::steps(Vec<3>& x, double dt, int k, Mat<3>* jacobian) const {
  if (jacobian == nullptr) {
    for (int s = 0; s < k; ++s) step(x, dt);
    return;
  }
  // Tangent linear of each stage: with P = dx/dx0, stage i's derivative is
  // T_i = J(stage point) (P + c_i dt T_{i-1}); the product over steps is the k-step derivative.
  Mat<3>& p = *jacobian;
  p.setIdentity();
  for (int s = 0; s < k; ++s) {
    const Vec<3> k1 = tendency(x);
    const Mat<3> t1 = tendency_jacobian(x) * p;
    const Vec<3> x2 = x + 0.5 * dt * k1;
    const Vec<3> k2 = tendency(x2);
    const Mat<3> t2 = tendency_jacobian(x2) * (p + 0.5 * dt * t1);
    const Vec<3> x3 = x + 0.5 * dt * k2;
    const Vec<3> k3 = tendency(x3);
    const Mat<3> t3 = tendency_jacobian(x3) * (p + 0.5 * dt * t2);
    const Vec<3> x4 = x + dt * k3;
    const Vec<3> k4 = tendency(x4);
    const Mat<3> t4 = tendency_jacobian(x4) * (p + dt * t3);
    x += (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    p += (dt / 6.0) * (t1 + 2.0 * t2 + 2.0 * t3 + t4);
  }
}

void Lorenz96::Workspace::resize(int n) {
  k1.resize(n);
  k2.resize(n);
  k3.resize(n);
  k4.resize(n);
  stage.resize(n);
}

Lorenz96::Lorenz96(int n, double forcing) : n_(n), forcing_(forcing) {
  require(n >= 4, "Lorenz-96: expected a dimension of at least 4, got {}", n);
  require(std::isfinite(forcing), "Lorenz-96: expected a finite forcing F, got {}", forcing);
}

void Lorenz96::tendency(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  const int n = n_;
  // The cyclic neighbours written out at the ends keep the interior loop free of modulo.
  out(0) = (x(1) - x(n - 2)) * x(n - 1) - x(0) + forcing_;
  out(1) = (x(2) - x(n - 1)) * x(0) - x(1) + forcing_;
  for (int i = 2; i < n - 1; ++i) out(i) = (x(i + 1) - x(i - 2)) * x(i - 1) - x(i) + forcing_;
  out(n - 1) = (x(0) - x(n - 3)) * x(n - 2) - x(n - 1) + forcing_;
}

void Lorenz96::apply_tendency_jacobian(const Eigen::VectorXd& x, const Eigen::MatrixXd& v,
                                       Eigen::MatrixXd& out) const {
  const int n = n_;
  // d f_i = x_{i-1} (dx_{i+1} - dx_{i-2}) + (x_{i+1} - x_{i-2}) dx_{i-1} - dx_i
  for (int i = 0; i < n; ++i) {
    const int ip1 = (i + 1) % n, im1 = (i + n - 1) % n, im2 = (i + n - 2) % n;
    out.row(i) = x(im1) * (v.row(ip1) - v.row(im2)) + (x(ip1) - x(im2)) * v.row(im1) - v.row(i);
  }
}

void Lorenz96::step(Eigen::VectorXd& x, double dt, Workspace& w) const {
  tendency(x, w.k1);
  w.stage = x + 0.5 * dt * w.k1;
  tendency(w.stage, w.k2);
  w.stage = x + 0.5 * dt * w.k2;
  tendency(w.stage, w.k3);
  w.stage = x + dt * w.k3;
  tendency(w.stage, w.k4);
  x += (dt / 6.0) * (w.k1 + 2.0 * w.k2 + 2.0 * w.k3 + w.k4);
}

void Lorenz96::steps(Eigen::VectorXd& x, double dt, int k, Workspace& w,
                     Eigen::MatrixXd* jacobian) const {
  if (jacobian == nullptr) {
    for (int s = 0; s < k; ++s) step(x, dt, w);
    return;
  }
  const int n = n_;
  Eigen::MatrixXd& p = *jacobian;
  p.setIdentity(n, n);
  for (auto* m : {&w.t1, &w.t2, &w.t3, &w.t4, &w.tstage}) m->resize(n, n);
  for (int s = 0; s < k; ++s) {  // the tangent linear of each stage, as in Lorenz63::steps
    tendency(x, w.k1);
    apply_tendency_jacobian(x, p, w.t1);
    w.stage = x + 0.5 * dt * w.k1;
    tendency(w.stage, w.k2);
    w.tstage = p + 0.5 * dt * w.t1;
    apply_tendency_jacobian(w.stage, w.tstage, w.t2);
    w.stage = x + 0.5 * dt * w.k2;
    tendency(w.stage, w.k3);
    w.tstage = p + 0.5 * dt * w.t2;
    apply_tendency_jacobian(w.stage, w.tstage, w.t3);
    w.stage = x + dt * w.k3;
    tendency(w.stage, w.k4);
    w.tstage = p + dt * w.t3;
    apply_tendency_jacobian(w.stage, w.tstage, w.t4);
    x += (dt / 6.0) * (w.k1 + 2.0 * w.k2 + 2.0 * w.k3 + w.k4);
    p += (dt / 6.0) * (w.t1 + 2.0 * w.t2 + 2.0 * w.t3 + w.t4);
  }
}

}  // namespace implicit::da
