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
#include <type_traits>

#include "implicit/core/types.hpp"
#include "implicit/core/weights.hpp"
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
  /// The range-bearing terms written out: one square root and one atan2 per term, and only the
  /// non-zero entries (the heading column of J is (0, -1); the second derivatives have no heading
  /// entries). This is the inner loop of implicit MCL; same formulas as evaluate_generic.
  double evaluate_range_bearing(const Pose& x, Vec<3>* gradient, Mat3* hessian,
                                Mat3* gauss_newton) const {
    const Vec<3> d = x - prediction_;
    const Vec<3> pd = prior_information_ * d;
    double value = constant_ + 0.5 * d.dot(pd);
    const bool derivatives = gradient || hessian || gauss_newton;
    const double n00 = noise_information_(0, 0), n01 = noise_information_(0, 1),
                 n11 = noise_information_(1, 1);
    // Measurement-term sums: gradient g0..g2, Gauss-Newton J^T N J (symmetric, upper part), and
    // the residual-weighted second derivatives (x, y block only).
    double g0 = 0, g1 = 0, g2 = 0;
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
    double c00 = 0, c01 = 0, c11 = 0;
    for (int i = 0; i < terms_; ++i) {
      const Landmark& m = landmarks_[i];
      const Measurement& z = measurements_[i];
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
};

/// Cholesky factorisation A = L L^T of a 3x3 symmetric positive definite matrix, written out.
/// The implicit proposal factors several 3x3 matrices per particle per step; Eigen's general LLT
/// (runtime loops, out-of-line) costs a few times more. Reads the lower triangle of A. Unlike
/// Eigen's LLT it rejects NaN pivots.
class Cholesky3 {
 public:
  /// Factors a; false (and the factor is unusable) when a is not numerically positive definite.
  bool compute(const Mat3& a) {
    const double d0 = a(0, 0);
    if (!(d0 > 0.0) || !std::isfinite(d0)) return false;
    const double l00 = std::sqrt(d0);
    const double l10 = a(1, 0) / l00, l20 = a(2, 0) / l00;
    const double d1 = a(1, 1) - l10 * l10;
    if (!(d1 > 0.0)) return false;
    const double l11 = std::sqrt(d1);
    const double l21 = (a(2, 1) - l20 * l10) / l11;
    const double d2 = a(2, 2) - l20 * l20 - l21 * l21;
    if (!(d2 > 0.0) || !std::isfinite(d2)) return false;
    l_ << l00, 0.0, 0.0, l10, l11, 0.0, l20, l21, std::sqrt(d2);
    return true;
  }
  const Mat3& matrixL() const { return l_; }
  /// log det L = 1/2 log det A (one log of the product; the diagonal is far from over/underflow
  /// for any covariance or information matrix of a pose).
  double log_det_L() const { return std::log(l_(0, 0) * l_(1, 1) * l_(2, 2)); }
  /// L y = b.
  Vec<3> solve_lower(const Vec<3>& b) const {
    const double y0 = b(0) / l_(0, 0);
    const double y1 = (b(1) - l_(1, 0) * y0) / l_(1, 1);
    const double y2 = (b(2) - l_(2, 0) * y0 - l_(2, 1) * y1) / l_(2, 2);
    return Vec<3>(y0, y1, y2);
  }
  /// L^T x = y.
  Vec<3> solve_upper(const Vec<3>& y) const {
    const double x2 = y(2) / l_(2, 2);
    const double x1 = (y(1) - l_(2, 1) * x2) / l_(1, 1);
    const double x0 = (y(0) - l_(1, 0) * x1 - l_(2, 0) * x2) / l_(0, 0);
    return Vec<3>(x0, x1, x2);
  }
  /// A x = b.
  Vec<3> solve(const Vec<3>& b) const { return solve_upper(solve_lower(b)); }
  /// A^-1 = L^-T L^-1, for when the inverse itself is the wanted quantity (an information matrix
  /// from a covariance), by solves with the factor.
  Mat3 inverse() const {
    Mat3 inv;
    for (int k = 0; k < 3; ++k) inv.col(k) = solve(Vec<3>::Unit(k));
    return inv;
  }

 private:
  Mat3 l_ = Mat3::Identity();
};

struct NewtonOptions {
  int max_iterations = 50;
  double step_tolerance = 1e-12;  ///< stop when max|step| <= this (spec §3.3)
  /// After a full exact-Newton step no larger than this has been taken (and its point evaluated),
  /// stop: convergence is quadratic, so the next step would be ~1e-10 relative - below anything
  /// the weights or the 1e-8 oracles of spec §3.7 can see - and computing it costs an evaluation.
  double final_step = 1e-5;
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
///
/// Cost control (this runs once per particle per laser update): every trial point is evaluated
/// with its derivatives, so an accepted step (the usual case) needs no second evaluation; a small
/// exact-Newton step ends the iteration (NewtonOptions::final_step); and a failed Armijo test at
/// the round-off floor of F stops at once instead of backtracking 40 times.
template <typename Objective>
NewtonResult minimize_newton(const Objective& f, const Pose& start, const NewtonOptions& opt = {}) {
  NewtonResult r;
  Pose x = start;
  Vec<3> g;
  Mat3 h, hgn;
  double fx = f.evaluate(x, &g, &h, &hgn);
  r.iterations = 1;
  if (!std::isfinite(fx) || !g.allFinite() || !hgn.allFinite()) return r;
  Cholesky3 chol;
  bool exact = false;    // chol factors the exact Hessian (else the Gauss-Newton one)
  bool current = false;  // chol factors a Hessian at x (not at an earlier point)
  for (int it = 0; it < opt.max_iterations; ++it) {
    exact = chol.compute(h);
    if (!exact && !chol.compute(hgn)) return r;
    current = true;
    const Vec<3> step = -chol.solve(g);
    if (!step.allFinite()) return r;
    const double size = step.cwiseAbs().maxCoeff();
    if (size <= opt.step_tolerance) {
      r.converged = true;
      break;
    }
    const double slope = g.dot(step);
    double t = 1.0;
    bool accepted = false, floor = false;
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
      // Both the change of F and the predicted decrease are at round-off: no point backtracking.
      const double ulp = 8.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(fx));
      if (std::isfinite(fn) && std::abs(fn - fx) <= ulp && -slope * t <= ulp) {
        floor = true;
        break;
      }
    }
    if (!accepted) {
      // No decrease: at the round-off floor of F near the minimum (or a kink of the wrapped
      // bearing). Keep x; it is as good a centre as any (the weights stay exact). chol still
      // factors the Hessian at x.
      r.converged = floor || size < 1e-6;
      break;
    }
    const double moved = t * size;
    current = false;
    x = xn;
    fx = fn;
    g = gn;
    h = hn;
    hgn = hgnn;
    if (moved <= opt.step_tolerance || (exact && t == 1.0 && size <= opt.final_step)) {
      r.converged = true;
      break;
    }
  }
  r.mu = x;
  r.phi = fx;
  if (!current) {  // ended right after a move: factor at mu, Gauss-Newton if H is not SPD there
    exact = chol.compute(h);
    if (!exact && !chol.compute(hgn)) return r;
  }
  r.gauss_newton_at_minimum = !exact;
  r.L = chol.matrixL();
  r.log_det_L = chol.log_det_L();
  r.ok = std::isfinite(r.log_det_L) && std::isfinite(r.phi);
  return r;
}

}  // namespace implicit::filter
