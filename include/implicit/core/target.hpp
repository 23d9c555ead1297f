#pragma once
// Targets: a negative log density F(x) = -log p(x) (up to a constant) with its gradient and
// Hessian.
//
// Implicit sampling needs F, grad F and the Hessian. A Target is any type with
//
//   static constexpr int Dim;                         // N, or Eigen::Dynamic
//   using Vector = Vec<Dim>;  using Matrix = Mat<Dim>;
//   int dim() const;
//   double evaluate(const Vector& x, Vector* grad, Matrix* hess) const;  // grad/hess may be null
//
// Return +infinity outside the support (the sample then gets weight 0). Three ready-made ways
// to build one from a user model, as in Ceres (one model, three derivative strategies):
//
//   auto a = make_analytic_target<2>(fn);     // fn(x, grad*, hess*) -> F: you supply derivatives
//   auto b = make_autodiff_target<2>(model);  // model(x) templated on the scalar: exact
//   derivatives auto c = make_numeric_target<2>(fn);      // fn(x) -> F: central finite differences
//
// Fixed sizes allocate nothing per evaluation. Common mistakes: forgetting that F is a NEGATIVE
// log density (a sign error makes the minimiser climb), and dropping factors 1/2 of Gaussians.
// check_derivatives() compares analytic derivatives with automatic ones and names the worst entry.

#include <cmath>
#include <concepts>
#include <limits>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

template <typename T>
concept Target = requires(const T& t, const typename T::Vector& x, typename T::Vector* g,
                          typename T::Matrix* h) {
  { T::Dim } -> std::convertible_to<int>;
  { t.dim() } -> std::convertible_to<int>;
  { t.evaluate(x, g, h) } -> std::convertible_to<double>;
};

/// F with user-supplied derivatives: fn(const Vec<N>& x, Vec<N>* grad, Mat<N>* hess) -> double.
template <int N, typename Fn>
class AnalyticTarget {
 public:
  static constexpr int Dim = N;
  using Vector = Vec<N>;
  using Matrix = Mat<N>;
  explicit AnalyticTarget(Fn fn, int dim = N) : fn_(std::move(fn)), dim_(dim) {
    require(dim_ > 0, "target dimension: expected a positive number, got {}", dim_);
  }
  int dim() const { return dim_; }
  double evaluate(const Vector& x, Vector* grad, Matrix* hess) const { return fn_(x, grad, hess); }

 private:
  Fn fn_;
  int dim_;
};

/// F from a functor templated on the scalar: model(const Eigen::Matrix<T, N, 1>&) -> T.
/// Value-only calls run the functor on doubles; derivative calls on second-order jets.
template <int N, typename Model>
class AutoDiffTarget {
 public:
  static constexpr int Dim = N;
  using Vector = Vec<N>;
  using Matrix = Mat<N>;
  explicit AutoDiffTarget(Model model, int dim = N) : model_(std::move(model)), dim_(dim) {
    require(dim_ > 0, "target dimension: expected a positive number, got {}", dim_);
  }
  int dim() const { return dim_; }
  double evaluate(const Vector& x, Vector* grad, Matrix* hess) const {
    if (!grad && !hess) return model_(x);
    auto [f, g, h] = autodiff_hessian<N>(model_, x);
    if (grad) *grad = g;
    if (hess) *hess = h;
    return f;
  }
  const Model& model() const { return model_; }

 private:
  Model model_;
  int dim_;
};

/// F from values only: fn(const Vec<N>& x) -> double; derivatives by central differences.
/// Gradient error O(h^2) with h = eps^(1/3) max(1,|x_i|); Hessian from values with eps^(1/4).
template <int N, typename Fn>
class NumericTarget {
 public:
  static constexpr int Dim = N;
  using Vector = Vec<N>;
  using Matrix = Mat<N>;
  explicit NumericTarget(Fn fn, int dim = N) : fn_(std::move(fn)), dim_(dim) {
    require(dim_ > 0, "target dimension: expected a positive number, got {}", dim_);
  }
  int dim() const { return dim_; }
  double evaluate(const Vector& x, Vector* grad, Matrix* hess) const {
    const double f0 = fn_(x);
    if (grad) {
      grad->resize(dim_);
      Vector xp = x;
      for (int i = 0; i < dim_; ++i) {
        const double h = 6.0554544523933395e-06 * std::max(1.0, std::abs(x(i)));  // eps^(1/3)
        xp(i) = x(i) + h;
        const double fp = fn_(xp);
        xp(i) = x(i) - h;
        const double fm = fn_(xp);
        xp(i) = x(i);
        (*grad)(i) = (fp - fm) / (2.0 * h);
      }
    }
    if (hess) {
      hess->resize(dim_, dim_);
      Vector xp = x;
      for (int i = 0; i < dim_; ++i) {
        const double hi = 1.220703125e-04 * std::max(1.0, std::abs(x(i)));  // eps^(1/4)
        xp(i) = x(i) + hi;
        const double fp = fn_(xp);
        xp(i) = x(i) - hi;
        const double fm = fn_(xp);
        xp(i) = x(i);
        (*hess)(i, i) = (fp - 2.0 * f0 + fm) / (hi * hi);
        for (int j = 0; j < i; ++j) {
          const double hj = 1.220703125e-04 * std::max(1.0, std::abs(x(j)));
          double s = 0.0;
          for (int a = -1; a <= 1; a += 2)
            for (int b = -1; b <= 1; b += 2) {
              xp(i) = x(i) + a * hi;
              xp(j) = x(j) + b * hj;
              s += a * b * fn_(xp);
            }
          xp(i) = x(i);
          xp(j) = x(j);
          (*hess)(i, j) = (*hess)(j, i) = s / (4.0 * hi * hj);
        }
      }
    }
    return f0;
  }

 private:
  Fn fn_;
  int dim_;
};

template <int N, typename Fn>
AnalyticTarget<N, Fn> make_analytic_target(Fn fn, int dim = N) {
  return AnalyticTarget<N, Fn>(std::move(fn), dim);
}
template <int N, typename Model>
AutoDiffTarget<N, Model> make_autodiff_target(Model model, int dim = N) {
  return AutoDiffTarget<N, Model>(std::move(model), dim);
}
template <int N, typename Fn>
NumericTarget<N, Fn> make_numeric_target(Fn fn, int dim = N) {
  return NumericTarget<N, Fn>(std::move(fn), dim);
}

/// Result of comparing a target's derivatives with automatic ones.
struct DerivativeCheck {
  double value_error = 0.0;     ///< |F - F_auto|
  double gradient_error = 0.0;  ///< worst |g_i - g_auto_i| / (1 + |g_auto_i|)
  int gradient_index = -1;      ///< where it occurs
  double hessian_error = 0.0;   ///< worst |H_ij - H_auto_ij| / (1 + |H_auto_ij|)
  int hessian_row = -1, hessian_col = -1;
  bool ok(double tolerance) const {
    return value_error <= tolerance && gradient_error <= tolerance && hessian_error <= tolerance;
  }
  std::string describe() const {
    return fmt::format(
        "value error {:.3e}; worst gradient entry {} (rel. error {:.3e}); worst Hessian entry "
        "({}, {}) (rel. error {:.3e})",
        value_error, gradient_index, gradient_error, hessian_row, hessian_col, hessian_error);
  }
};

/// Compares `target`'s value, gradient and Hessian at x with those of `model` (a functor
/// templated on the scalar type, differentiated automatically). Use it to test your own
/// analytic derivatives: `EXPECT_TRUE(check_derivatives(t, model, x).ok(1e-9))`.
template <Target T, typename Model>
DerivativeCheck check_derivatives(const T& target, const Model& model,
                                  const typename T::Vector& x) {
  require(x.size() == target.dim(), "check_derivatives: expected a point of dimension {}, got {}",
          target.dim(), x.size());
  // Pre-sized (and NaN-filled), so analytic functors for dynamic sizes need not resize and
  // entries they forget to set are reported instead of read uninitialised.
  typename T::Vector g =
      T::Vector::Constant(target.dim(), std::numeric_limits<double>::quiet_NaN());
  typename T::Matrix h =
      T::Matrix::Constant(target.dim(), target.dim(), std::numeric_limits<double>::quiet_NaN());
  const double f = target.evaluate(x, &g, &h);
  auto [fa, ga, ha] = autodiff_hessian<T::Dim>(model, x);
  DerivativeCheck c;
  c.value_error = std::abs(f - fa);
  for (int i = 0; i < target.dim(); ++i) {
    const double e = std::abs(g(i) - ga(i)) / (1.0 + std::abs(ga(i)));
    if (!(e <= c.gradient_error)) {  // also catches NaN
      c.gradient_error = std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
      c.gradient_index = i;
    }
    for (int j = 0; j < target.dim(); ++j) {
      const double eh = std::abs(h(i, j) - ha(i, j)) / (1.0 + std::abs(ha(i, j)));
      if (!(eh <= c.hessian_error)) {
        c.hessian_error = std::isnan(eh) ? std::numeric_limits<double>::infinity() : eh;
        c.hessian_row = i;
        c.hessian_col = j;
      }
    }
  }
  return c;
}

}  // namespace implicit
