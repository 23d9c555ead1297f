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
//   NewtonResult r = minimize_newton(f, prediction);   // mu, phi, L with H = L L^T
//
// The minimiser is a hand-written 3-D Newton on fixed-size matrices rather than the generic
// core::minimize: it runs once per particle per laser update (hundreds of thousands of times per
// run), and avoiding the generic target wrapper, Levenberg retries and dynamic checks makes it
// several times faster. Exact Hessian when the sensor provides second derivatives; whenever its
// Cholesky fails (round-off, or far from the minimum where the residual terms make it indefinite),
// the Gauss-Newton Hessian (always SPD) is used instead - for the Newton step, and at the minimum
// for the sampling matrix L, so sampling and weight always use the same L.
//
// Common mistakes: dropping the 1/2 (samples p^2, spec E22), sharing one Sigma1 between particles
// (E23), forgetting -log det L in the weight (E24).

#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "implicit/core/types.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

using robot::Control;
using robot::Landmark;
using robot::Mat2;
using robot::Mat23;
using robot::Mat3;
using robot::Measurement;
using robot::Pose;

template <robot::LandmarkSensor Sensor>
class MclObjective {
 public:
  static constexpr int kMaxTerms = 32;  ///< detections per update (the Car Park has at most 6)

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
  bool add(const Landmark& m, const Measurement& z) {
    if (terms_ == kMaxTerms) return false;
    landmarks_[terms_] = m;
    measurements_[terms_] = z;
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
    const Vec<3> d = x - prediction_;
    const Vec<3> pd = prior_information_ * d;
    double value = constant_ + 0.5 * d.dot(pd);
    if (gradient) *gradient = pd;
    if (hessian) *hessian = prior_information_;
    if (gauss_newton) *gauss_newton = prior_information_;
    for (int i = 0; i < terms_; ++i) {
      const Landmark& m = landmarks_[i];
      const Measurement e = sensor_->residual(sensor_->predict(x, m), measurements_[i]);
      const Measurement s = noise_information_ * e;
      value += 0.5 * e.dot(s);
      if (!gradient && !hessian && !gauss_newton) continue;
      const Mat23 j = sensor_->jacobian_pose(x, m);
      if (gradient) *gradient += j.transpose() * s;
      if (hessian || gauss_newton) {
        const Mat3 jnj = j.transpose() * noise_information_ * j;
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
  const Sensor* sensor_ = nullptr;
  Mat2 noise_information_ = Mat2::Identity();
  Pose prediction_ = Pose::Zero();
  Mat3 prior_information_ = Mat3::Identity();
  double constant_ = 0.0;
  int terms_ = 0;
  std::array<Landmark, kMaxTerms> landmarks_;
  std::array<Measurement, kMaxTerms> measurements_;
};

struct NewtonOptions {
  int max_iterations = 50;
  double step_tolerance = 1e-12;  ///< stop when max|step| <= this (spec §3.3)
  double armijo = 1e-4;
  int max_backtracks = 40;
};

/// The Gaussian approximation at the minimum that both maps use.
struct NewtonResult {
  Pose mu = Pose::Zero();
  double phi = std::numeric_limits<double>::quiet_NaN();  ///< F(mu), constants included
  Mat3 L = Mat3::Identity();  ///< lower Cholesky factor of the Hessian used at mu
  double log_det_L = 0.0;
  int iterations = 0;                    ///< objective evaluations with derivatives
  bool gauss_newton_at_minimum = false;  ///< exact Hessian not SPD at mu: Gauss-Newton used
  bool converged = false;
  bool ok = false;  ///< false: F not finite at the start, or no SPD Hessian (do not sample)
};

/// Damped Newton from `start` (use the prediction f^j). Never throws.
template <typename Objective>
NewtonResult minimize_newton(const Objective& f, const Pose& start, const NewtonOptions& opt = {}) {
  NewtonResult r;
  Pose x = start;
  Vec<3> g;
  Mat3 h, hgn;
  double fx = f.evaluate(x, &g, &h, &hgn);
  r.iterations = 1;
  if (!std::isfinite(fx) || !g.allFinite() || !hgn.allFinite()) return r;
  Eigen::LLT<Mat3> llt;
  for (int it = 0; it < opt.max_iterations; ++it) {
    llt.compute(h);
    if (llt.info() != Eigen::Success || !h.allFinite()) {
      llt.compute(hgn);
      if (llt.info() != Eigen::Success) return r;
    }
    const Vec<3> step = -llt.solve(g);
    if (!step.allFinite()) return r;
    if (step.cwiseAbs().maxCoeff() <= opt.step_tolerance) {
      r.converged = true;
      break;
    }
    const double slope = g.dot(step);
    double t = 1.0;
    bool accepted = false;
    Pose xn;
    Vec<3> gn;
    Mat3 hn, hgnn;
    double fn = 0.0;
    for (int k = 0; k <= opt.max_backtracks; ++k, t *= 0.5) {
      xn = x + t * step;
      fn = f.evaluate(xn, &gn, &hn, &hgnn);
      ++r.iterations;
      // A non-finite F (Newton stepped onto a landmark) is a failed trial step.
      if (std::isfinite(fn) && fn <= fx + opt.armijo * t * slope) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      // No decrease: at the round-off floor of F near the minimum (or a kink of the wrapped
      // bearing). Keep x; it is as good a centre as any (the weights stay exact).
      r.converged = step.cwiseAbs().maxCoeff() < 1e-6;
      break;
    }
    const double moved = (t * step).cwiseAbs().maxCoeff();
    x = xn;
    fx = fn;
    g = gn;
    h = hn;
    hgn = hgnn;
    if (moved <= opt.step_tolerance) {
      r.converged = true;
      break;
    }
  }
  r.mu = x;
  r.phi = fx;
  llt.compute(h);
  if (llt.info() != Eigen::Success || !h.allFinite()) {
    r.gauss_newton_at_minimum = true;
    llt.compute(hgn);
    if (llt.info() != Eigen::Success) return r;
  }
  r.L = llt.matrixL();
  r.log_det_L = std::log(r.L(0, 0)) + std::log(r.L(1, 1)) + std::log(r.L(2, 2));
  r.ok = std::isfinite(r.log_det_L) && std::isfinite(r.phi);
  return r;
}

}  // namespace implicit::filter
