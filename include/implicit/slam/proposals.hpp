#pragma once
// The functions F that implicit SLAM minimises and samples around (spec §3.3, §3.5, §3.7).
//
// PoseObjective (3-D, known landmarks): for one particle with predicted pose f, process noise
// Sigma1 and landmark terms (m_i, z_i, S_i),
//   F(x) = 1/2 |x - f|^2_{Sigma1^-1} + sum_i 1/2 e_i^T S_i^-1 e_i,   e_i = (r_i - z_r, wrap(b_i -
//   z_b))
// plus constant() = 1/2 log det(2 pi Sigma1) + sum_i 1/2 log det(2 pi S_i), which the weights keep.
// Implicit SLAM (A) uses S_i = Sigma2 and the particle's point landmark: this is implicit MCL.
// Implicit SLAM (B) uses S_i = H_m P_i H_m^T + Sigma2 frozen at (f, m_i).
//
// NewLandmarkObjective (5-D, a new landmark in (A)): F(x, theta) = 1/2|x - f|^2_{Sigma1^-1}
// + 1/2 e(x, theta)^T Sigma2^-1 e(x, theta) with a flat prior on theta. Its minimiser is closed
// form, mu = (f, g(f, z)) with F(mu) = 0, and H = blockdiag(Sigma1^-1, 0) + J^T Sigma2^-1 J.
//
// Both are minimised and sampled by the implicit-sampling kernel (core/newton.hpp,
// core/implicit_maps.hpp); only F and its derivatives live here:
//
//   PoseObjective F(f, sigma1, terms);
//   PoseMinimum r = newton_minimize<SmallFactor<3>>(F, f, pose_newton_options(20, 1e-10));
//   Pose x;
//   double log_w = linear_map(WithConstant{F}, r.x, r.factor, xi, x);  // if pose_minimum_usable(r)
//
// Mistakes to avoid: dropping constant() (WithConstant) or log det L from the weight (they differ
// between particles, spec E23/E24); differentiating at range 0 (F is +inf there, and the line
// search treats it as a failed step).

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/range_bearing.hpp"

namespace implicit::slam {

/// 1/2 e^T S^-1 e for one landmark, S given by its Cholesky factor.
struct LandmarkTerm {
  Vec<2> landmark = Vec<2>::Zero();
  Vec<2> z = Vec<2>::Zero();
  Eigen::LLT<Mat<2>> s_llt;
  double half_log_det_2pi_s = 0.0;  ///< 1/2 log det(2 pi S)

  /// Factorises S; returns false when S is not positive definite.
  bool set(const Vec<2>& m, const Vec<2>& measurement, const Mat<2>& s) {
    landmark = m;
    z = measurement;
    s_llt.compute(s);
    if (s_llt.info() != Eigen::Success) return false;
    const Mat<2> l = s_llt.matrixL();
    half_log_det_2pi_s = kLog2Pi + std::log(l(0, 0)) + std::log(l(1, 1));
    return std::isfinite(half_log_det_2pi_s);
  }
};

class PoseObjective {
 public:
  /// `sigma1` must be SPD (check ok()). `terms` must outlive the objective.
  PoseObjective(const Vec<3>& f, const Mat<3>& sigma1, std::span<const LandmarkTerm> terms)
      : f_(f), terms_(terms), llt1_(sigma1) {
    ok_ = llt1_.info() == Eigen::Success;
    if (!ok_) return;
    precision_ = llt1_.solve(Mat<3>::Identity());
    precision_ = 0.5 * (precision_ + precision_.transpose()).eval();
    const Mat<3> l = llt1_.matrixL();
    constant_ = 1.5 * kLog2Pi + l.diagonal().array().log().sum();
    for (const auto& t : terms_) constant_ += t.half_log_det_2pi_s;
  }

  bool ok() const { return ok_ && std::isfinite(constant_); }
  const Vec<3>& prior_mean() const { return f_; }
  const Mat<3>& prior_precision() const { return precision_; }
  /// 1/2 log det(2 pi Sigma1) + sum_i 1/2 log det(2 pi S_i).
  double constant() const { return constant_; }

  /// F(x) without constant(); +inf when not finite (e.g. x on a landmark). No Jacobians: this is
  /// what backtracking and the weight call.
  double value(const Vec<3>& x) const {
    const Vec<3> d = x - f_;
    double v = 0.5 * d.dot(precision_ * d);
    for (const auto& t : terms_) {
      const Residual res(t, x);
      v += 0.5 * res.e.dot(t.s_llt.solve(res.e));
    }
    return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
  }

  /// F(x), its gradient, exact Hessian and Gauss-Newton Hessian (exact minus residual terms).
  double evaluate(const Vec<3>& x, Vec<3>& grad, Mat<3>& hess, Mat<3>& hess_gn) const {
    const Vec<3> d = x - f_;
    grad = precision_ * d;
    double v = 0.5 * d.dot(grad);
    hess_gn = precision_;
    Mat<2> second = Mat<2>::Zero();  // residual-weighted second derivatives (x, y block)
    for (const auto& t : terms_) {
      const Residual res(t, x);
      const double dx = res.dx, dy = res.dy, r2 = res.r2, r = res.r;
      Eigen::Matrix<double, 2, 3> j;
      j << dx / r, dy / r, 0.0, -dy / r2, dx / r2, -1.0;
      const Vec<2> w = t.s_llt.solve(res.e);
      v += 0.5 * res.e.dot(w);
      grad.noalias() += j.transpose() * w;
      const Eigen::Matrix<double, 2, 3> sj = t.s_llt.solve(j);
      hess_gn.noalias() += j.transpose() * sj;
      const double r3 = r2 * r, r4 = r2 * r2;
      second(0, 0) += w(0) * dy * dy / r3 + w(1) * 2.0 * dx * dy / r4;
      second(0, 1) += -w(0) * dx * dy / r3 + w(1) * (dy * dy - dx * dx) / r4;
      second(1, 1) += w(0) * dx * dx / r3 - w(1) * 2.0 * dx * dy / r4;
    }
    second(1, 0) = second(0, 1);
    hess = hess_gn;
    hess.topLeftCorner<2, 2>() += second;
    return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
  }

  /// The kernel's form (core/newton.hpp): the value alone, or all derivatives (the Newton loop
  /// asks for the gradient, Hessian and Gauss-Newton Hessian together).
  double evaluate(const Vec<3>& x, Vec<3>* grad, Mat<3>* hess, Mat<3>* hess_gn = nullptr) const {
    if (grad == nullptr && hess == nullptr && hess_gn == nullptr) return value(x);
    if (grad != nullptr && hess != nullptr && hess_gn != nullptr)
      return evaluate(x, *grad, *hess, *hess_gn);
    Vec<3> g;
    Mat<3> h, gn;
    const double v = evaluate(x, g, h, gn);
    if (grad != nullptr) *grad = g;
    if (hess != nullptr) *hess = h;
    if (hess_gn != nullptr) *hess_gn = gn;
    return v;
  }

 private:
  /// e = (range - z_r, wrap(bearing - z_b)) at x, with the offsets its derivatives need.
  struct Residual {
    double dx, dy, r2, r;
    Vec<2> e;
    Residual(const LandmarkTerm& t, const Vec<3>& x)
        : dx(x(0) - t.landmark(0)),
          dy(x(1) - t.landmark(1)),
          r2(dx * dx + dy * dy),
          r(std::sqrt(r2)),
          e(r - t.z(0), wrap_angle(std::atan2(-dy, -dx) - x(2) + kPi / 2.0 - t.z(1))) {}
  };

  Vec<3> f_;
  std::span<const LandmarkTerm> terms_;
  Eigen::LLT<Mat<3>> llt1_;
  Mat<3> precision_ = Mat<3>::Zero();
  double constant_ = 0.0;
  bool ok_ = false;
};

/// The pose minimum of implicit SLAM: mu = x, the factor of the Hessian used for sampling, and
/// how it was found (exact_factor false: the exact Hessian was not SPD, Gauss-Newton was used).
using PoseMinimum = NewtonMinimum<SmallFactor<3>>;

/// The kernel's options for the pose solve: exact Hessian, Gauss-Newton when it is not SPD,
/// Armijo backtracking (40 halvings) where a non-finite F is a failed step, and one stopping
/// rule: the Newton decrement g^T H^-1 g below `decrement_tolerance`. The centre is then within
/// sqrt(tol) posterior standard deviations of the minimiser, and the factor already computed
/// there is the one returned (no extra evaluation). Any centre and any SPD Hessian give exact
/// weights (spec §1.1), so the tolerance only trades efficiency.
inline NewtonOptions pose_newton_options(int max_iterations, double decrement_tolerance) {
  NewtonOptions o;
  o.max_iterations = max_iterations;
  o.decrement_tolerance = decrement_tolerance;
  o.gradient_tolerance = 0.0;
  o.step_tolerance = 0.0;
  o.final_step = 0.0;
  o.armijo = 1e-4;
  o.max_backtracks = 40;
  o.fallback = HessianFallback::kGaussNewton;
  return o;
}

/// The minimum can be sampled: a finite point with an SPD factor of the Hessian there.
inline bool pose_minimum_usable(const PoseMinimum& r) {
  return r.factor_ok && r.status != MinimizeStatus::kNonFinite && r.x.allFinite();
}

/// F with its constant, for the weight: log_weight.hpp needs F(X) including every constant that
/// differs between particles, while Newton minimises F without it (its round-off floor stays
/// that of F).
template <typename Objective>
struct WithConstant {
  const Objective& F;
  template <typename V, typename G, typename H>
  double evaluate(const V& x, G grad, H hess) const {
    return F.evaluate(x, grad, hess) + F.constant();
  }
};
template <typename Objective>
WithConstant(const Objective&) -> WithConstant<Objective>;

/// A detection z of a known landmark whose estimate is N(mean, cov) (cov = 0: point landmark).
struct KnownLandmark {
  std::size_t slot = 0;  ///< index in the particle's map
  Vec<2> z = Vec<2>::Zero();
  Vec<2> mean = Vec<2>::Zero();
  Mat<2> cov = Mat<2>::Zero();
};

/// J_h_m (2x2), the Jacobian of h(x, m) in the landmark: the sensor's jacobian_landmark when it
/// has one, else minus the position columns of J_h_x (h depends on m - (x, y) only).
template <robot::LandmarkSensor Sensor>
Mat<2> landmark_jacobian(const Sensor& sensor, const Vec<3>& x, const Vec<2>& m) {
  if constexpr (requires { sensor.jacobian_landmark(x, m); })
    return sensor.jacobian_landmark(x, m);
  else
    return -sensor.jacobian_pose(x, m).template leftCols<2>();
}

/// FastSLAM 2.0's proposal: the measurement model linearised at the prediction f (Montemerlo et
/// al. 2003), all detections jointly:
///   Lambda = Sigma1^-1 + sum_i H_x,i^T Q_i^-1 H_x,i,   Q_i = Sigma2 + H_m,i P_i H_m,i^T,
///   mean = f + Lambda^-1 sum_i H_x,i^T Q_i^-1 nu_i,   nu_i = wrap(z_i - h(f, m_i)),
/// and the weight increment log N(nu; 0, H_x Sigma1 H_x^T + blockdiag(Q_i)), evaluated in the
/// information form (Woodbury; no inverse of the stacked covariance).
struct LinearizedProposal {
  Vec<3> mean = Vec<3>::Zero();
  Mat<3> L = Mat<3>::Identity();  ///< lower Cholesky factor of Lambda (sample mean + L^-T xi)
  double log_weight = 0.0;
  bool ok = false;
};

template <robot::LandmarkSensor Sensor>
LinearizedProposal linearized_optimal_proposal(const Sensor& sensor, const Vec<3>& f,
                                               const Eigen::LLT<Mat<3>>& sigma1_llt,
                                               std::span<const KnownLandmark> known) {
  LinearizedProposal out;
  const Mat<2>& r = sensor.noise_covariance();
  Mat<3> lambda = sigma1_llt.solve(Mat<3>::Identity());
  Vec<3> b = Vec<3>::Zero();
  double quad = 0.0, log_det_q = 0.0;
  for (const auto& k : known) {
    const Eigen::Matrix<double, 2, 3> hx = sensor.jacobian_pose(f, k.mean);
    const Mat<2> hm = -hx.leftCols<2>();
    const Eigen::LLT<Mat<2>> llt(hm * k.cov * hm.transpose() + r);
    if (llt.info() != Eigen::Success) return out;
    const Vec<2> nu = -sensor.residual(sensor.predict(f, k.mean), k.z);
    const Vec<2> qnu = llt.solve(nu);
    lambda.noalias() += hx.transpose() * llt.solve(hx);
    b.noalias() += hx.transpose() * qnu;
    quad += nu.dot(qnu);
    const Mat<2> l = llt.matrixL();
    log_det_q += 2.0 * (std::log(l(0, 0)) + std::log(l(1, 1)));
  }
  lambda = 0.5 * (lambda + lambda.transpose()).eval();
  const Eigen::LLT<Mat<3>> lltl(lambda);
  if (lltl.info() != Eigen::Success) return out;
  const Vec<3> shift = lltl.solve(b);
  out.L = lltl.matrixL();
  const Mat<3> l1 = sigma1_llt.matrixL();
  // det(H Sigma1 H^T + Q) = det Q det Sigma1 det Lambda; quadratic form by Woodbury.
  const double log_det = log_det_q + 2.0 * l1.diagonal().array().log().sum() +
                         2.0 * out.L.diagonal().array().log().sum();
  out.log_weight =
      -0.5 * (quad - b.dot(shift)) - 0.5 * log_det - static_cast<double>(known.size()) * kLog2Pi;
  out.mean = f + shift;
  out.ok = std::isfinite(out.log_weight) && out.mean.allFinite();
  return out;
}

/// The 5-D F of a new landmark in implicit SLAM (A), variables p = (x, y, beta, theta1, theta2).
class NewLandmarkObjective {
 public:
  NewLandmarkObjective(const Vec<3>& f, const Mat<3>& sigma1, const Vec<2>& z, const Mat<2>& sigma2)
      : f_(f), z_(z), llt1_(sigma1), llt2_(sigma2) {
    ok_ = llt1_.info() == Eigen::Success && llt2_.info() == Eigen::Success;
    if (!ok_) return;
    precision1_ = llt1_.solve(Mat<3>::Identity());
    precision1_ = 0.5 * (precision1_ + precision1_.transpose()).eval();
    const Mat<3> l1 = llt1_.matrixL();
    const Mat<2> l2 = llt2_.matrixL();
    constant_ = 1.5 * kLog2Pi + l1.diagonal().array().log().sum() + kLog2Pi +
                l2.diagonal().array().log().sum();
  }
  bool ok() const { return ok_; }
  /// 1/2 log det(2 pi Sigma1) + 1/2 log det(2 pi Sigma2).
  double constant() const { return constant_; }

  /// The closed-form minimiser (f, g(f, z)); F there is 0.
  Vec<5> minimizer() const {
    Vec<5> p;
    p.head<3>() = f_;
    p.tail<2>() = robot::RangeBearingSensor::inverse(f_, z_);
    return p;
  }

  /// F(p) without constant(); optional gradient and exact Hessian. +inf when not finite.
  double evaluate(const Vec<5>& p, Vec<5>* grad = nullptr, Mat<5>* hess = nullptr) const {
    const Vec<3> d = p.head<3>() - f_;
    const Vec<3> pd = precision1_ * d;
    const double dx = p(0) - p(3), dy = p(1) - p(4);
    const double r2 = dx * dx + dy * dy, r = std::sqrt(r2);
    const Vec<2> e(r - z_(0), wrap_angle(std::atan2(-dy, -dx) - p(2) + kPi / 2.0 - z_(1)));
    const Vec<2> w = llt2_.solve(e);
    const double v = 0.5 * d.dot(pd) + 0.5 * e.dot(w);
    if (!std::isfinite(v)) return std::numeric_limits<double>::infinity();
    const Eigen::Matrix<double, 2, 5> j = jacobian(dx, dy, r2, r);
    if (grad != nullptr) {
      grad->setZero();
      grad->head<3>() = pd;
      *grad += j.transpose() * w;
    }
    if (hess != nullptr) {
      hess->setZero();
      hess->topLeftCorner<3, 3>() = precision1_;
      *hess += j.transpose() * llt2_.solve(j);
      const double r3 = r2 * r, r4 = r2 * r2;
      Mat<2> k;  // sum_a w_a * (second derivative of e_a in (x, y)); theta block is +k, cross -k
      k(0, 0) = w(0) * dy * dy / r3 + w(1) * 2.0 * dx * dy / r4;
      k(0, 1) = -w(0) * dx * dy / r3 + w(1) * (dy * dy - dx * dx) / r4;
      k(1, 1) = w(0) * dx * dx / r3 - w(1) * 2.0 * dx * dy / r4;
      k(1, 0) = k(0, 1);
      hess->block<2, 2>(0, 0) += k;
      hess->block<2, 2>(3, 3) += k;
      hess->block<2, 2>(0, 3) -= k;
      hess->block<2, 2>(3, 0) -= k;
    }
    return v;
  }

  /// H at the minimiser: blockdiag(Sigma1^-1, 0) + J^T Sigma2^-1 J (the residual is zero there).
  Mat<5> hessian_at_minimizer() const {
    Mat<5> h;
    evaluate(minimizer(), nullptr, &h);
    return h;
  }

 private:
  static Eigen::Matrix<double, 2, 5> jacobian(double dx, double dy, double r2, double r) {
    Eigen::Matrix<double, 2, 5> j;
    j << dx / r, dy / r, 0.0, -dx / r, -dy / r,  //
        -dy / r2, dx / r2, -1.0, dy / r2, -dx / r2;
    return j;
  }
  Vec<3> f_;
  Vec<2> z_;
  Eigen::LLT<Mat<3>> llt1_;
  Eigen::LLT<Mat<2>> llt2_;
  Mat<3> precision1_ = Mat<3>::Zero();
  double constant_ = 0.0;
  bool ok_ = false;
};

}  // namespace implicit::slam
