#pragma once
// The functions F that implicit SLAM minimises and samples around (spec §3.3, §3.5, §3.7).
//
// The pose F (3-D, known landmarks) is the filter layer's (filter/mcl_objective.hpp): for one
// particle with predicted pose f, process noise Sigma1 and landmark terms (m_i, z_i, S_i),
//   F(x) = 1/2 |x - f|^2_{Sigma1^-1} + sum_i 1/2 e_i^T S_i^-1 e_i + constant,
//   constant = 1/2 log det(2 pi Sigma1) + sum_i 1/2 log det(2 pi S_i),
// which the weights keep. Implicit SLAM (A) uses S_i = Sigma2 and the particle's point landmark:
// this is implicit MCL. Implicit SLAM (B) uses S_i = H_m P_i H_m^T + Sigma2 frozen at (f, m_i),
// a term with its own information matrix. set_pose_objective() builds it for a particle.
//
// NewLandmarkObjective (5-D, a new landmark in (A)): F(x, theta) = 1/2|x - f|^2_{Sigma1^-1}
// + 1/2 e(x, theta)^T Sigma2^-1 e(x, theta) with a flat prior on theta. Its minimiser is closed
// form, mu = (f, g(f, z)) with F(mu) = 0, and H = blockdiag(Sigma1^-1, 0) + J^T Sigma2^-1 J.
//
// Both are minimised and sampled by the implicit-sampling kernel (core/newton.hpp,
// core/implicit_maps.hpp):
//
//   PoseObjective<> F;
//   if (set_pose_objective(F, sensor, f, sigma1_llt, known, point_landmarks)) {
//     filter::PoseMinimum r = newton_minimize<SmallFactor<3>>(F, f, pose_newton_options(20,
//     1e-10)); Pose x; double log_w = linear_map(F, r.x, r.factor, xi, x);  // if filter::usable(r)
//   }
//
// Mistakes to avoid: dropping the constant or log det L from the weight (they differ between
// particles, spec E23/E24); differentiating at range 0 (F is +inf there, and the line search
// treats it as a failed step).

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include <Eigen/Cholesky>

#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/mcl_objective.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/range_bearing.hpp"

namespace implicit::slam {

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

/// Known landmarks a particle's pose objective holds at one step (the Car Park sees at most 6 per
/// step, Victoria Park about 7 on average); the particle filter refuses a step with more
/// (ImplicitPoseProposal::max_known_landmarks), set_pose_objective returns false.
inline constexpr int kMaxKnownPerStep = 64;

/// The pose objective of implicit SLAM: the filter layer's, one term per known landmark.
template <robot::LandmarkSensor Sensor = robot::RangeBearingSensor>
using PoseObjective = filter::MclObjective<Sensor, kMaxKnownPerStep>;

/// Sets F for one particle: prior N(f, Sigma1), a term per known landmark with S_i = Sigma2
/// (point_landmarks, (A)) or H_m P_i H_m^T + Sigma2 at (f, m_i) ((B)), and the constant. Returns
/// false when some S_i is not SPD or there are more than kMaxKnownPerStep landmarks.
template <robot::LandmarkSensor Sensor>
bool set_pose_objective(PoseObjective<Sensor>& F, const Sensor& sensor, const Vec<3>& f,
                        const Eigen::LLT<Mat<3>>& sigma1_llt, std::span<const KnownLandmark> known,
                        bool point_landmarks) {
  if (known.size() > static_cast<std::size_t>(kMaxKnownPerStep)) return false;
  Mat<3> precision = sigma1_llt.solve(Mat<3>::Identity());
  precision = 0.5 * (precision + precision.transpose()).eval();
  const Mat<3> l1 = sigma1_llt.matrixL();
  const Mat<2>& r = sensor.noise_covariance();
  F.reset(sensor, Mat<2>::Identity(), f, precision,
          gaussian_log_normaliser(3, l1.diagonal().array().log().sum()));
  for (const KnownLandmark& k : known) {
    Mat<2> s = r;
    if (!point_landmarks) {
      const Mat<2> hm = landmark_jacobian(sensor, f, k.mean);
      s += hm * k.cov * hm.transpose();
    }
    const Eigen::LLT<Mat<2>> llt(s);
    if (llt.info() != Eigen::Success) return false;
    const Mat<2> l = llt.matrixL();
    const Mat<2> information = llt.solve(Mat<2>::Identity());
    F.add(k.mean, k.z, 0.5 * (information + information.transpose()));
    F.add_constant(gaussian_log_normaliser(2, std::log(l(0, 0))) + std::log(l(1, 1)));
  }
  return std::isfinite(F.constant());
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
  out.log_weight = -0.5 * (quad - b.dot(shift)) - 0.5 * log_det -
                   gaussian_log_normaliser(2 * static_cast<int>(known.size()), 0.0);
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
    constant_ = gaussian_log_normaliser(3, l1.diagonal().array().log().sum()) +
                gaussian_log_normaliser(2, 0.0) + l2.diagonal().array().log().sum();
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
