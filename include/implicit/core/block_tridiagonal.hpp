#pragma once
// Block-tridiagonal symmetric positive definite systems: the Hessians of discretised paths.
//
// A path y_1..y_n of states in R^B, coupled only between neighbours (y_{i-1}, y_i), has a Hessian
// with B x B blocks on the diagonal and the first sub/super-diagonal only. Its Cholesky factor
// L has the same pattern (no fill-in), so factorising, solving, sampling x = mu + L^{-T} xi and
// log det L all cost O(n B^3) instead of O((nB)^3). BandedFactor<B> (gaussian_factor.hpp) gives
// the Newton kernel this factorisation; minimize_banded() (banded.hpp) runs it on banded targets.
//
//   implicit::BlockTridiagonal<1> H(n);               // n blocks of size 1 (a tridiagonal matrix)
//   H.diagonal[i](0, 0) = 2.0;  H.subdiagonal[i](0, 0) = -1.0;   // H(i+1, i) = H(i, i+1)
//   implicit::BlockTridiagonalCholesky<1> chol;
//   if (chol.compute(H)) { chol.upper_solve_in_place(xi); double ld = chol.log_det_L(); }
//
// Common mistakes: storing the SUPER-diagonal block in `subdiagonal` (it is H(i+1, i), the
// transpose of H(i, i+1)); and calling solve before checking that compute() returned true.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit {
/// Symmetric block-tridiagonal matrix with n blocks of size B x B (fixed B).
template <int B>
struct BlockTridiagonal {
  static_assert(B > 0, "BlockTridiagonal: the block size must be a compile-time constant");
  std::vector<Mat<B>> diagonal;     ///< n blocks H(i, i)
  std::vector<Mat<B>> subdiagonal;  ///< n - 1 blocks H(i + 1, i)

  BlockTridiagonal() = default;
  explicit BlockTridiagonal(int num_blocks) { resize(num_blocks); }

  int num_blocks() const { return static_cast<int>(diagonal.size()); }
  int size() const { return num_blocks() * B; }

  /// Sets the number of blocks and zeroes every entry (keeps capacity: no allocation when the
  /// size does not grow).
  void resize(int num_blocks) {
    diagonal.resize(static_cast<std::size_t>(std::max(num_blocks, 0)));
    subdiagonal.resize(static_cast<std::size_t>(std::max(num_blocks - 1, 0)));
    set_zero();
  }
  void set_zero() {
    for (auto& d : diagonal) d.setZero();
    for (auto& s : subdiagonal) s.setZero();
  }

  /// y = H x.
  Eigen::VectorXd multiply(const Eigen::VectorXd& x) const {
    const int n = num_blocks();
    Eigen::VectorXd y(x.size());
    for (int i = 0; i < n; ++i) {
      Vec<B> yi = diagonal[i] * x.template segment<B>(i * B);
      if (i > 0) yi += subdiagonal[i - 1] * x.template segment<B>((i - 1) * B);
      if (i + 1 < n) yi += subdiagonal[i].transpose() * x.template segment<B>((i + 1) * B);
      y.template segment<B>(i * B) = yi;
    }
    return y;
  }

  /// Dense copy (tests and small problems only).
  Eigen::MatrixXd to_dense() const {
    const int n = num_blocks();
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(size(), size());
    for (int i = 0; i < n; ++i) {
      d.template block<B, B>(i * B, i * B) = diagonal[i];
      if (i + 1 < n) {
        d.template block<B, B>((i + 1) * B, i * B) = subdiagonal[i];
        d.template block<B, B>(i * B, (i + 1) * B) = subdiagonal[i].transpose();
      }
    }
    return d;
  }

  /// Adds lambda to every diagonal entry (Levenberg damping).
  void add_to_diagonal(double lambda) {
    for (auto& d : diagonal) d.diagonal().array() += lambda;
  }

  bool all_finite() const {
    for (const auto& d : diagonal)
      if (!d.allFinite()) return false;
    for (const auto& s : subdiagonal)
      if (!s.allFinite()) return false;
    return true;
  }
};

/// Cholesky factorisation H = L L^T of an SPD block-tridiagonal matrix. L is block lower
/// bidiagonal: diagonal blocks L(i, i) (lower triangular) and sub-diagonal blocks L(i + 1, i).
template <int B>
class BlockTridiagonalCholesky {
 public:
  BlockTridiagonalCholesky() = default;
  explicit BlockTridiagonalCholesky(const BlockTridiagonal<B>& h) { compute(h); }

  /// Factorises h. Returns false (and ok() is false) if h is not positive definite or not
  /// finite. O(n B^3).
  bool compute(const BlockTridiagonal<B>& h) {
    const int n = h.num_blocks();
    diag_.resize(static_cast<std::size_t>(n));
    sub_.resize(static_cast<std::size_t>(std::max(n - 1, 0)));
    inverse_diagonal_.resize(static_cast<std::size_t>(n * B));
    ok_ = n > 0;
    log_det_L_ = 0.0;
    Mat<B> schur;
    for (int i = 0; i < n && ok_; ++i) {
      schur = h.diagonal[i];
      if (i > 0) schur.noalias() -= sub_[i - 1] * sub_[i - 1].transpose();
      Eigen::LLT<Mat<B>> llt(schur);
      if (llt.info() != Eigen::Success || !schur.allFinite()) {
        ok_ = false;
        break;
      }
      diag_[i] = llt.matrixL();
      for (int k = 0; k < B; ++k) {
        log_det_L_ += std::log(diag_[i](k, k));
        inverse_diagonal_[static_cast<std::size_t>(i * B + k)] = 1.0 / diag_[i](k, k);
      }
      if (i + 1 < n) {
        // L(i+1, i) = H(i+1, i) L(i, i)^{-T}  <=>  L(i, i) L(i+1, i)^T = H(i+1, i)^T.
        Mat<B> t = h.subdiagonal[i].transpose();
        diag_[i].template triangularView<Eigen::Lower>().solveInPlace(t);
        sub_[i] = t.transpose();
      }
    }
    if (!ok_ || !std::isfinite(log_det_L_)) {
      ok_ = false;
      log_det_L_ = std::numeric_limits<double>::quiet_NaN();
    }
    return ok_;
  }

  bool ok() const { return ok_; }
  int num_blocks() const { return static_cast<int>(diag_.size()); }
  int size() const { return num_blocks() * B; }

  /// log det L = 1/2 log det H.
  double log_det_L() const { return log_det_L_; }

  /// b <- L^{-1} b (forward substitution).
  template <typename Derived>
  void lower_solve_in_place(Eigen::MatrixBase<Derived>& b) const {
    const int n = num_blocks();
    for (int i = 0; i < n; ++i) {
      Vec<B> r = b.template segment<B>(i * B);
      if (i > 0) r.noalias() -= sub_[i - 1] * b.template segment<B>((i - 1) * B);
      forward_substitute(diag_[i], &inverse_diagonal_[static_cast<std::size_t>(i * B)], r);
      b.template segment<B>(i * B) = r;
    }
  }

  /// b <- L^{-T} b (back substitution). Maps a reference sample xi to the offset L^{-T} xi,
  /// whose covariance is H^{-1}.
  template <typename Derived>
  void upper_solve_in_place(Eigen::MatrixBase<Derived>& b) const {
    const int n = num_blocks();
    for (int i = n - 1; i >= 0; --i) {
      Vec<B> r = b.template segment<B>(i * B);
      if (i + 1 < n) r.noalias() -= sub_[i].transpose() * b.template segment<B>((i + 1) * B);
      back_substitute(diag_[i], &inverse_diagonal_[static_cast<std::size_t>(i * B)], r);
      b.template segment<B>(i * B) = r;
    }
  }

  /// b <- H^{-1} b.
  template <typename Derived>
  void solve_in_place(Eigen::MatrixBase<Derived>& b) const {
    lower_solve_in_place(b);
    upper_solve_in_place(b);
  }

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const {
    Eigen::VectorXd x = b;
    solve_in_place(x);
    return x;
  }

  /// L^T v: with v = y - mu, |L^T (y - mu)|^2 is the Mahalanobis distance of y under N(mu, H^-1).
  Eigen::VectorXd upper_multiply(const Eigen::VectorXd& v) const {
    const int n = num_blocks();
    Eigen::VectorXd r(v.size());
    for (int i = 0; i < n; ++i) {
      Vec<B> ri = diag_[i].transpose() * v.template segment<B>(i * B);
      if (i + 1 < n) ri.noalias() += sub_[i].transpose() * v.template segment<B>((i + 1) * B);
      r.template segment<B>(i * B) = ri;
    }
    return r;
  }

  const Mat<B>& diagonal_block(int i) const { return diag_[static_cast<std::size_t>(i)]; }
  const Mat<B>& subdiagonal_block(int i) const { return sub_[static_cast<std::size_t>(i)]; }

 private:
  // The small triangular solves by hand, multiplying by the stored reciprocals of L's diagonal:
  // the solve is one long dependency chain through the blocks, and it is the inner loop of every
  // sample, so a division's latency on the chain is what it costs (bench_control).
  // r <- L^{-1} r for a lower-triangular block L.
  static void forward_substitute(const Mat<B>& L, const double* inverse_diagonal, Vec<B>& r) {
    for (int a = 0; a < B; ++a) {
      double v = r(a);
      for (int c = 0; c < a; ++c) v -= L(a, c) * r(c);
      r(a) = v * inverse_diagonal[a];
    }
  }
  // r <- L^{-T} r.
  static void back_substitute(const Mat<B>& L, const double* inverse_diagonal, Vec<B>& r) {
    for (int a = B - 1; a >= 0; --a) {
      double v = r(a);
      for (int c = a + 1; c < B; ++c) v -= L(c, a) * r(c);
      r(a) = v * inverse_diagonal[a];
    }
  }

  std::vector<Mat<B>> diag_;
  std::vector<Mat<B>> sub_;
  std::vector<double> inverse_diagonal_;  // 1 / L(i, i)(k, k), block by block
  double log_det_L_ = std::numeric_limits<double>::quiet_NaN();
  bool ok_ = false;
};

extern template struct BlockTridiagonal<1>;
extern template struct BlockTridiagonal<2>;
extern template class BlockTridiagonalCholesky<1>;
extern template class BlockTridiagonalCholesky<2>;

}  // namespace implicit
