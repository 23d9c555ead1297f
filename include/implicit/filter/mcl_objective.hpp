#pragma once
// F^j, the negative log density that implicit MCL minimises and samples for particle j (spec §3.3):
//
//   F^j(x) = 1/2 |x - f^j|^2_{Sigma1^-1} + 1/2 sum_i e_i(x)^T Sigma2^-1 e_i(x) + constant,
//   e_i(x) = residual(h(x, m_i), z_i)            (range-bearing: bearing wrapped)
//
// with f^j = predict(X^j_{n-1}, u_n) and Sigma1^j = process_covariance(X^j_{n-1}, u_n) per
// particle. The constant (1/2 log det 2 pi Sigma1^j + p/2 log det 2 pi Sigma2 - (dropped) log p0)
// must be kept: the weights of different particles come from different F^j (spec §1.4, E23, E24).
//
//   MclObjective<RangeBearingSensor> f;
//   f.reset(sensor, noise_information, prediction, prior_information, constant);
//   f.add(landmark, z);                       // one term per associated detection
//   PoseMinimum r = newton_minimize<SmallFactor<3>>(f, prediction, mcl_newton_options());
//   // r.x = mu, r.value = phi, r.factor: H = L L^T (usable(r): fit to sample)
//
// F is minimised by the kernel's Newton (core/newton.hpp) on fixed-size matrices (SmallFactor<3>,
// no heap): it runs once per particle per laser update. Exact Hessian when the sensor provides
// second derivatives; whenever its Cholesky fails (round-off, or far from the minimum where the
// residual terms make it indefinite), the Gauss-Newton Hessian that evaluate() also returns
// (always SPD with a prior) is used instead - for the Newton step, and at the minimum for the
// sampling matrix L, so sampling and weight always use the same L.
//
// Common mistakes: dropping the 1/2 (samples p^2, spec E22), sharing one Sigma1 between particles
// (E23), forgetting -log det L in the weight (E24).

#include <array>
#include <cmath>
#include <type_traits>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/landmark_observation.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

using robot::Control;
using robot::Landmark;
using robot::Mat2;
using robot::Mat23;
using robot::Mat3;
using robot::Measurement;
using robot::Pose;

template <robot::LandmarkSensor Sensor, int MaxTerms = robot::kMaxDetectionsPerStep>
class MclObjective {
 public:
  /// Detections per update (the Car Park has at most 6): what the landmark model accepts.
  static constexpr int kMaxTerms = MaxTerms;

  /// Starts a new F: prior N(prediction, prior_information^-1), no measurement terms.
  void reset(const Sensor& sensor, const Mat2& noise_information, const Pose& prediction,
             const Mat3& prior_information, double constant) {
    sensor_ = &sensor;
    noise_information_ = noise_information;
    prediction_ = prediction;
    prior_information_ = prior_information;
    constant_ = constant;
    terms_ = 0;
  }

  /// Adds the term of landmark m observed as z. Returns false (and adds nothing) when full.
  bool add(const Landmark& m, const Measurement& z) { return add(m, z, noise_information_); }

  /// The same with the term's own information S^-1 in place of Sigma2^-1: implicit SLAM (B),
  /// whose landmarks are uncertain, has S = H_m P H_m^T + Sigma2 per landmark (spec §3.5).
  bool add(const Landmark& m, const Measurement& z, const Mat2& information) {
    if (terms_ == kMaxTerms) return false;
    landmarks_[terms_] = m;
    measurements_[terms_] = z;
    information_[terms_] = information;
    ++terms_;
    return true;
  }

  int terms() const { return terms_; }
  double constant() const { return constant_; }
  void add_constant(double c) { constant_ += c; }
  const Pose& prediction() const { return prediction_; }

  /// F(x); optionally the gradient, the exact Hessian and the Gauss-Newton Hessian (drops the
  /// residual-times-second-derivative terms). Non-finite at a landmark (r = 0).
  double evaluate(const Pose& x, Vec<3>* gradient = nullptr, Mat3* hessian = nullptr,
                  Mat3* gauss_newton = nullptr) const {
    if constexpr (std::is_same_v<Sensor, robot::RangeBearingSensor>)
      return evaluate_range_bearing(x, gradient, hessian, gauss_newton);
    else
      return evaluate_generic(x, gradient, hessian, gauss_newton);
  }

  /// The sensor-agnostic evaluation through the LandmarkSensor interface (the reference for the
  /// range-bearing fast path; tests compare the two).
  double evaluate_generic(const Pose& x, Vec<3>* gradient = nullptr, Mat3* hessian = nullptr,
                          Mat3* gauss_newton = nullptr) const {
    const Vec<3> d = x - prediction_;
    const Vec<3> pd = prior_information_ * d;
    double value = constant_ + 0.5 * d.dot(pd);
    if (gradient) *gradient = pd;
    if (hessian) *hessian = prior_information_;
    if (gauss_newton) *gauss_newton = prior_information_;
    for (int i = 0; i < terms_; ++i) {
      const Landmark& m = landmarks_[i];
      const Measurement e = sensor_->residual(sensor_->predict(x, m), measurements_[i]);
      const Mat2& information = information_[i];
      const Measurement s = information * e;
      value += 0.5 * e.dot(s);
      if (!gradient && !hessian && !gauss_newton) continue;
      const Mat23 j = sensor_->jacobian_pose(x, m);
      if (gradient) *gradient += j.transpose() * s;
      if (hessian || gauss_newton) {
        const Mat3 jnj = j.transpose() * information * j;
        if (gauss_newton) *gauss_newton += jnj;
        if (hessian) {
          *hessian += jnj;
          if constexpr (robot::LandmarkSensorWithHessian<Sensor>) {
            Mat3 h0, h1;
            sensor_->hessian_pose(x, m, h0, h1);
            *hessian += s(0) * h0 + s(1) * h1;
          }
        }
      }
    }
    return value;
  }

 private:
  /// The range-bearing terms written out: one square root and one atan2 per term, and only the
  /// non-zero entries (the heading column of J is (0, -1); the second derivatives have no heading
  /// entries). This is the inner loop of implicit MCL; same formulas as evaluate_generic.
  double evaluate_range_bearing(const Pose& x, Vec<3>* gradient, Mat3* hessian,
                                Mat3* gauss_newton) const {
    const Vec<3> d = x - prediction_;
    const Vec<3> pd = prior_information_ * d;
    double value = constant_ + 0.5 * d.dot(pd);
    const bool derivatives = gradient || hessian || gauss_newton;
    // Measurement-term sums: gradient g0..g2, Gauss-Newton J^T N J (symmetric, upper part), and
    // the residual-weighted second derivatives (x, y block only).
    double g0 = 0, g1 = 0, g2 = 0;
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
    double c00 = 0, c01 = 0, c11 = 0;
    for (int i = 0; i < terms_; ++i) {
      const Landmark& m = landmarks_[i];
      const Measurement& z = measurements_[i];
      const double n00 = information_[i](0, 0), n01 = information_[i](0, 1),
                   n11 = information_[i](1, 1);
      const double dx = x(0) - m(0), dy = x(1) - m(1);
      const double r2 = dx * dx + dy * dy, r = std::sqrt(r2);
      const double e0 = r - z(0);
      const double e1 = wrap_angle(std::atan2(-dy, -dx) - x(2) + kPi / 2.0 - z(1));
      const double s0 = n00 * e0 + n01 * e1, s1 = n01 * e0 + n11 * e1;
      value += 0.5 * (e0 * s0 + e1 * s1);
      if (!derivatives) continue;
      // J = [[ja0, ja1, 0], [jb0, jb1, -1]]
      const double inv_r = 1.0 / r, inv_r2 = inv_r * inv_r;
      const double ja0 = dx * inv_r, ja1 = dy * inv_r;
      const double jb0 = -dy * inv_r2, jb1 = dx * inv_r2;
      g0 += s0 * ja0 + s1 * jb0;
      g1 += s0 * ja1 + s1 * jb1;
      g2 -= s1;
      // N J, column by column; (J^T N J)_kl = J_col_k . (N J)_col_l.
      const double u00 = n00 * ja0 + n01 * jb0, u10 = n01 * ja0 + n11 * jb0;
      const double u01 = n00 * ja1 + n01 * jb1, u11 = n01 * ja1 + n11 * jb1;
      a00 += ja0 * u00 + jb0 * u10;
      a01 += ja0 * u01 + jb0 * u11;
      a11 += ja1 * u01 + jb1 * u11;
      a02 -= u10;  // J col 2 = (0, -1): (J^T N J)_k2 = -(N J)_1k
      a12 -= u11;
      a22 += n11;
      if (hessian) {
        // s0 d2r + s1 d2b with d2r = [[dy^2, -dx dy], [., dx^2]] / r^3 and
        // d2b = [[2 dx dy, dy^2 - dx^2], [., -2 dx dy]] / r^4 (spec §3.3).
        const double w0 = s0 * inv_r2 * inv_r, w1 = s1 * inv_r2 * inv_r2;
        const double dxdy = dx * dy;
        c00 += w0 * dy * dy + 2.0 * w1 * dxdy;
        c01 += -w0 * dxdy + w1 * (dy * dy - dx * dx);
        c11 += w0 * dx * dx - 2.0 * w1 * dxdy;
      }
    }
    if (gradient) *gradient = pd + Vec<3>(g0, g1, g2);
    if (hessian || gauss_newton) {
      Mat3 gn = prior_information_;
      gn(0, 0) += a00;
      gn(0, 1) += a01;
      gn(1, 0) += a01;
      gn(0, 2) += a02;
      gn(2, 0) += a02;
      gn(1, 1) += a11;
      gn(1, 2) += a12;
      gn(2, 1) += a12;
      gn(2, 2) += a22;
      if (gauss_newton) *gauss_newton = gn;
      if (hessian) {
        *hessian = gn;
        (*hessian)(0, 0) += c00;
        (*hessian)(0, 1) += c01;
        (*hessian)(1, 0) += c01;
        (*hessian)(1, 1) += c11;
      }
    }
    return value;
  }

  const Sensor* sensor_ = nullptr;
  Mat2 noise_information_ = Mat2::Identity();
  Pose prediction_ = Pose::Zero();
  Mat3 prior_information_ = Mat3::Identity();
  double constant_ = 0.0;
  int terms_ = 0;
  std::array<Landmark, kMaxTerms> landmarks_;
  std::array<Measurement, kMaxTerms> measurements_;
  std::array<Mat2, kMaxTerms> information_;  ///< Sigma2^-1, or the term's own S^-1
};

/// The Gaussian approximation at the minimum that both maps use: mu = x, phi = value (constants
/// included), and the factor H = L L^T used at mu (exact Hessian, else Gauss-Newton:
/// !exact_factor). `evaluations` counts every evaluation of F.
using PoseMinimum = NewtonMinimum<SmallFactor<3>>;

/// The stopping rules of implicit MCL (spec §3.3) for newton_minimize<SmallFactor<3>>: an absolute
/// step tolerance of 1e-12 and no gradient rule; the Gauss-Newton Hessian (always SPD with a
/// prior) whenever the exact one is not SPD; and `final_step`: after a full exact-Newton step no
/// larger than 1e-5, stop, since convergence is quadratic and the next step (~1e-10 relative) is
/// below anything the weights or the 1e-8 oracles of spec §3.7 can see, yet would cost an
/// evaluation. This runs once per particle per laser update.
inline NewtonOptions mcl_newton_options() {
  NewtonOptions o;
  o.max_iterations = 50;
  o.gradient_tolerance = 0.0;
  o.step_tolerance = 1e-12;
  o.relative_step_tolerance = false;
  o.final_step = 1e-5;
  o.armijo = 1e-4;
  o.max_backtracks = 40;
  o.fallback = HessianFallback::kGaussNewton;
  o.damping = false;  // nothing SPD: the proposal samples the prior, a start of the cover is lost
  return o;
}

/// True when the minimum can centre the maps: F finite at mu and an SPD factor there.
inline bool usable(const PoseMinimum& r) {
  return r.factor_ok && r.status != MinimizeStatus::kNonFinite && std::isfinite(r.value) &&
         std::isfinite(r.factor.log_det_L());
}

}  // namespace implicit::filter
