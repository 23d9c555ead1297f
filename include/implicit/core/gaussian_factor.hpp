#pragma once
// Gaussian factors: the H = L L^T of implicit sampling, in the storage the problem needs.
//
// The implicit-sampling kernel (newton.hpp, linear_map.hpp, random_map.hpp, log_weight.hpp) never
// touches a matrix directly: it asks a factor for three things.
//
//   template <typename F> concept GaussianFactor:   // what sampling and weighting need
//     typename F::Vector;
//     double log_det_L() const;                     // 1/2 log det H
//     void upper_solve_in_place(Vector& v) const;   // v <- L^{-T} v  (x = mu + L^{-T} xi)
//     void solve_in_place(Vector& v) const;         // v <- H^{-1} v  (the Newton step)
//   template <typename F> concept FactorModel:      // ... plus factorising, for the minimiser
//     typename F::Hessian;
//     bool compute(const Hessian& h);               // false when h is not SPD (or not finite)
//     static double diagonal_scale(const Hessian&); // max |H_ii|, the scale of Levenberg damping
//     static void add_to_diagonal(Hessian&, double);
//
// Models: DenseFactor<N> (any size, Eigen's LLT; N may be Eigen::Dynamic), SmallFactor<N> (fixed
// N, never on the heap; the 3x3 case is written out, it is the inner loop of implicit MCL and
// SLAM), and BandedFactor<B> (block-tridiagonal Hessians of paths, O(n B^3), the Cholesky of
// banded.hpp). LowerFactorView wraps
// a stored lower-triangular L (a Laplace approximation) for sampling only.

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/core/block_tridiagonal.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

template <typename F>
concept GaussianFactor = requires(const F& f, typename F::Vector& v) {
  typename F::Vector;
  { f.log_det_L() } -> std::convertible_to<double>;
  f.upper_solve_in_place(v);
  f.solve_in_place(v);
};

template <typename F>
concept FactorModel = GaussianFactor<F> && requires(F& f, typename F::Hessian& h, double lambda) {
  typename F::Hessian;
  { f.compute(h) } -> std::same_as<bool>;
  { F::diagonal_scale(h) } -> std::convertible_to<double>;
  F::add_to_diagonal(h, lambda);
};

namespace detail {
/// Damping helpers shared by the Eigen-matrix models.
template <int N>
struct DenseDiagonal {
  static double diagonal_scale(const Mat<N>& h) { return h.diagonal().cwiseAbs().maxCoeff(); }
  static void add_to_diagonal(Mat<N>& h, double lambda) { h.diagonal().array() += lambda; }
};
}  // namespace detail

/// H = L L^T by Eigen's LLT, any size (fixed sizes do not allocate).
template <int N>
class DenseFactor : public detail::DenseDiagonal<N> {
 public:
  using Vector = Vec<N>;
  using Hessian = Mat<N>;

  bool compute(const Hessian& h) {
    llt_.compute(h);
    ok_ = llt_.info() == Eigen::Success && h.allFinite();
    log_det_L_ = ok_ ? llt_.matrixLLT().diagonal().array().log().sum()
                     : std::numeric_limits<double>::quiet_NaN();
    ok_ = ok_ && std::isfinite(log_det_L_);
    return ok_;
  }
  bool ok() const { return ok_; }
  double log_det_L() const { return log_det_L_; }
  Mat<N> matrixL() const { return llt_.matrixL(); }
  void upper_solve_in_place(Vector& v) const { llt_.matrixU().solveInPlace(v); }
  void solve_in_place(Vector& v) const { llt_.solveInPlace(v); }

 private:
  Eigen::LLT<Mat<N>> llt_;
  double log_det_L_ = std::numeric_limits<double>::quiet_NaN();
  bool ok_ = false;
};

/// Fixed-size factor that never allocates (the 3x3 and 5x5 Hessians of MCL and SLAM).
template <int N>
class SmallFactor : public DenseFactor<N> {
  static_assert(N > 0, "SmallFactor: the size must be a compile-time constant");
};

/// The 3x3 case written out: the implicit proposal factors several 3x3 matrices per particle per
/// step, and Eigen's general LLT (runtime loops, out of line) costs a few times more. Reads the
/// lower triangle. Unlike Eigen's LLT it rejects NaN pivots.
template <>
class SmallFactor<3> : public detail::DenseDiagonal<3> {
 public:
  using Vector = Vec<3>;
  using Hessian = Mat<3>;

  /// Factors a; false (and the factor is unusable) when a is not numerically positive definite.
  bool compute(const Mat<3>& a) {
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
  const Mat<3>& matrixL() const { return l_; }
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
  void upper_solve_in_place(Vector& v) const { v = solve_upper(v); }
  void solve_in_place(Vector& v) const { v = solve(v); }
  /// A^-1 = L^-T L^-1, for when the inverse itself is the wanted quantity (an information matrix
  /// from a covariance), by solves with the factor.
  Mat<3> inverse() const {
    Mat<3> inv;
    for (int k = 0; k < 3; ++k) inv.col(k) = solve(Vec<3>::Unit(k));
    return inv;
  }

 private:
  Mat<3> l_ = Mat<3>::Identity();
};

/// The banded model: `BlockTridiagonalCholesky<B>` with the FactorModel interface.
template <int B>
class BandedFactor : public BlockTridiagonalCholesky<B> {
 public:
  using Vector = Eigen::VectorXd;
  using Hessian = BlockTridiagonal<B>;
  bool compute(const Hessian& h) { return BlockTridiagonalCholesky<B>::compute(h); }
  void upper_solve_in_place(Vector& v) const {
    BlockTridiagonalCholesky<B>::upper_solve_in_place(v);
  }
  void solve_in_place(Vector& v) const { BlockTridiagonalCholesky<B>::solve_in_place(v); }
  static double diagonal_scale(const Hessian& h) {
    double scale = 0.0;
    for (const auto& d : h.diagonal) scale = std::max(scale, d.diagonal().cwiseAbs().maxCoeff());
    return scale;
  }
  static void add_to_diagonal(Hessian& h, double lambda) { h.add_to_diagonal(lambda); }
};

/// A lower-triangular L stored elsewhere (a Laplace approximation), for sampling and weighting.
/// Holds a reference: the matrix must outlive the view.
template <int N>
class LowerFactorView {
 public:
  using Vector = Vec<N>;
  LowerFactorView(const Mat<N>& L, double log_det_L) : L_(L), log_det_L_(log_det_L) {}
  double log_det_L() const { return log_det_L_; }
  void upper_solve_in_place(Vector& v) const {
    if constexpr (N != Eigen::Dynamic && N <= 8) {
      // By hand for small fixed sizes: Eigen's triangular solve costs more than the rest of a
      // linear-map sample at N = 3 and 5 (bench_core BM_LinearMapSample).
      // The reciprocals do not depend on v: their divisions overlap instead of lying on the
      // solve's dependency chain.
      for (int a = N - 1; a >= 0; --a) {
        const double inverse = 1.0 / L_(a, a);
        double r = v(a);
        for (int c = a + 1; c < N; ++c) r -= L_(c, a) * v(c);
        v(a) = r * inverse;
      }
    } else {
      L_.transpose().template triangularView<Eigen::Upper>().solveInPlace(v);
    }
  }
  void solve_in_place(Vector& v) const {
    L_.template triangularView<Eigen::Lower>().solveInPlace(v);
    upper_solve_in_place(v);
  }

 private:
  const Mat<N>& L_;
  double log_det_L_;
};

}  // namespace implicit
