#pragma once
// Second-order forward-mode automatic differentiation.
//
// Jet2<N> carries a value, its gradient (N) and its Hessian (N x N) through every arithmetic
// operation, so one evaluation of a functor templated on the scalar type gives F, grad F and
// the Hessian together. We use this instead of Eigen's nested AutoDiffScalar because the nested
// form stores N inner derivative vectors per entry (N^2 redundant scalars, heap allocation for
// dynamic sizes) and lacks atan2/log1p for the inner type; a dedicated second-order jet is about
// N^2 flops per operation and allocation-free for fixed N, which matters in per-particle loops.
//
//   auto F = [](const auto& x) { using std::exp; return x(0) * x(0) + exp(x(1)); };
//   auto [value, grad, hess] = implicit::autodiff_hessian<2>(F, x);
//
// Branches on values work (comparisons look at the value only); derivatives of non-smooth
// points follow the branch taken.

#include <cmath>
#include <tuple>

#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit {

template <int N>
struct Jet2 {
  double v = 0.0;
  Vec<N> g;
  Mat<N> h;

  Jet2() : g(Vec<N>::Zero(N == Eigen::Dynamic ? 0 : N)), h(Mat<N>::Zero(g.size(), g.size())) {}
  // A constant: value c, zero derivatives of dimension `dim`. For N = Eigen::Dynamic the default
  // is a size-0 constant, which adopts the size of the first sized jet it is combined with.
  explicit Jet2(double c, int dim = N)
      : v(c),
        g(Vec<N>::Zero(dim < 0 ? 0 : dim)),
        h(Mat<N>::Zero(dim < 0 ? 0 : dim, dim < 0 ? 0 : dim)) {}
  Jet2(double value, const Vec<N>& grad, const Mat<N>& hess) : v(value), g(grad), h(hess) {}

  /// The i-th independent variable with value x (gradient e_i).
  static Jet2 variable(double x, int i, int dim = N) {
    Jet2 j(x, dim);
    j.g(i) = 1.0;
    return j;
  }

  Jet2& operator+=(const Jet2& o) { return *this = *this + o; }
  Jet2& operator-=(const Jet2& o) { return *this = *this - o; }
  Jet2& operator*=(const Jet2& o) { return *this = *this * o; }
  Jet2& operator/=(const Jet2& o) { return *this = *this / o; }
  Jet2& operator+=(double c) {
    v += c;
    return *this;
  }
  Jet2& operator-=(double c) {
    v -= c;
    return *this;
  }
  Jet2& operator*=(double c) { return *this = *this * c; }
  Jet2& operator/=(double c) { return *this = *this * (1.0 / c); }
};

namespace detail {
// Mixing a constant-size-0 Jet (default-constructed, e.g. Eigen's zero) with a sized one.
template <int N>
inline void match(Jet2<N>& a, const Jet2<N>& b) {
  if constexpr (N == Eigen::Dynamic) {
    if (a.g.size() == 0 && b.g.size() != 0) {
      a.g = Vec<N>::Zero(b.g.size());
      a.h = Mat<N>::Zero(b.g.size(), b.g.size());
    }
  }
}
// f(a) with first and second derivative d1, d2 of f at a.v.
template <int N>
inline Jet2<N> chain(const Jet2<N>& a, double f, double d1, double d2) {
  return Jet2<N>(f, d1 * a.g, d1 * a.h + d2 * a.g * a.g.transpose());
}
}  // namespace detail

template <int N>
inline Jet2<N> operator+(Jet2<N> a, Jet2<N> b) {
  detail::match(a, b);
  detail::match(b, a);
  return Jet2<N>(a.v + b.v, a.g + b.g, a.h + b.h);
}
template <int N>
inline Jet2<N> operator-(Jet2<N> a, Jet2<N> b) {
  detail::match(a, b);
  detail::match(b, a);
  return Jet2<N>(a.v - b.v, a.g - b.g, a.h - b.h);
}
template <int N>
inline Jet2<N> operator-(const Jet2<N>& a) {
  return Jet2<N>(-a.v, -a.g, -a.h);
}
template <int N>
inline Jet2<N> operator*(Jet2<N> a, Jet2<N> b) {
  detail::match(a, b);
  detail::match(b, a);
  Mat<N> gh = a.g * b.g.transpose();
  return Jet2<N>(a.v * b.v, a.v * b.g + b.v * a.g, a.v * b.h + b.v * a.h + gh + gh.transpose());
}
template <int N>
inline Jet2<N> operator/(const Jet2<N>& a, const Jet2<N>& b) {
  const double inv = 1.0 / b.v;
  return a * detail::chain(b, inv, -inv * inv, 2.0 * inv * inv * inv);
}
template <int N>
inline Jet2<N> operator+(const Jet2<N>& a, double c) {
  return Jet2<N>(a.v + c, a.g, a.h);
}
template <int N>
inline Jet2<N> operator+(double c, const Jet2<N>& a) {
  return a + c;
}
template <int N>
inline Jet2<N> operator-(const Jet2<N>& a, double c) {
  return Jet2<N>(a.v - c, a.g, a.h);
}
template <int N>
inline Jet2<N> operator-(double c, const Jet2<N>& a) {
  return Jet2<N>(c - a.v, -a.g, -a.h);
}
template <int N>
inline Jet2<N> operator*(const Jet2<N>& a, double c) {
  return Jet2<N>(a.v * c, a.g * c, a.h * c);
}
template <int N>
inline Jet2<N> operator*(double c, const Jet2<N>& a) {
  return a * c;
}
template <int N>
inline Jet2<N> operator/(const Jet2<N>& a, double c) {
  return a * (1.0 / c);
}
template <int N>
inline Jet2<N> operator/(double c, const Jet2<N>& b) {
  const double inv = 1.0 / b.v;
  return detail::chain(b, c * inv, -c * inv * inv, 2.0 * c * inv * inv * inv);
}

// Comparisons look at values only (for branches inside user functors).
#define IMPLICIT_JET_COMPARE(op)                                \
  template <int N>                                              \
  inline bool operator op(const Jet2<N>& a, const Jet2<N>& b) { \
    return a.v op b.v;                                          \
  }                                                             \
  template <int N>                                              \
  inline bool operator op(const Jet2<N>& a, double b) {         \
    return a.v op b;                                            \
  }                                                             \
  template <int N>                                              \
  inline bool operator op(double a, const Jet2<N>& b) {         \
    return a op b.v;                                            \
  }
IMPLICIT_JET_COMPARE(<)
IMPLICIT_JET_COMPARE(<=)
IMPLICIT_JET_COMPARE(>)
IMPLICIT_JET_COMPARE(>=)
IMPLICIT_JET_COMPARE(==)
IMPLICIT_JET_COMPARE(!=)
#undef IMPLICIT_JET_COMPARE

template <int N>
inline Jet2<N> sqrt(const Jet2<N>& a) {
  const double s = std::sqrt(a.v);
  return detail::chain(a, s, 0.5 / s, -0.25 / (s * a.v));
}
template <int N>
inline Jet2<N> exp(const Jet2<N>& a) {
  const double e = std::exp(a.v);
  return detail::chain(a, e, e, e);
}
template <int N>
inline Jet2<N> log(const Jet2<N>& a) {
  return detail::chain(a, std::log(a.v), 1.0 / a.v, -1.0 / (a.v * a.v));
}
template <int N>
inline Jet2<N> log1p(const Jet2<N>& a) {
  const double d = 1.0 / (1.0 + a.v);
  return detail::chain(a, std::log1p(a.v), d, -d * d);
}
template <int N>
inline Jet2<N> sin(const Jet2<N>& a) {
  const double s = std::sin(a.v);
  return detail::chain(a, s, std::cos(a.v), -s);
}
template <int N>
inline Jet2<N> cos(const Jet2<N>& a) {
  const double c = std::cos(a.v);
  return detail::chain(a, c, -std::sin(a.v), -c);
}
template <int N>
inline Jet2<N> tan(const Jet2<N>& a) {
  const double t = std::tan(a.v);
  const double d1 = 1.0 + t * t;
  return detail::chain(a, t, d1, 2.0 * t * d1);
}
template <int N>
inline Jet2<N> atan(const Jet2<N>& a) {
  const double d1 = 1.0 / (1.0 + a.v * a.v);
  return detail::chain(a, std::atan(a.v), d1, -2.0 * a.v * d1 * d1);
}
template <int N>
inline Jet2<N> tanh(const Jet2<N>& a) {
  const double t = std::tanh(a.v);
  const double d1 = 1.0 - t * t;
  return detail::chain(a, t, d1, -2.0 * t * d1);
}
template <int N>
inline Jet2<N> abs(const Jet2<N>& a) {
  return a.v < 0 ? -a : a;
}
template <int N>
inline Jet2<N> pow(const Jet2<N>& a, double p) {
  const double f = std::pow(a.v, p);
  return detail::chain(a, f, p * std::pow(a.v, p - 1.0), p * (p - 1.0) * std::pow(a.v, p - 2.0));
}
/// atan2(y, x) with both arguments differentiated.
template <int N>
inline Jet2<N> atan2(Jet2<N> y, Jet2<N> x) {
  detail::match(y, x);
  detail::match(x, y);
  const double r2 = x.v * x.v + y.v * y.v;
  const double fy = x.v / r2, fx = -y.v / r2;
  const double fyy = -2.0 * x.v * y.v / (r2 * r2), fxx = -fyy;
  const double fxy = (y.v * y.v - x.v * x.v) / (r2 * r2);
  Mat<N> cross = x.g * y.g.transpose();
  return Jet2<N>(std::atan2(y.v, x.v), fy * y.g + fx * x.g,
                 fy * y.h + fx * x.h + fyy * y.g * y.g.transpose() + fxx * x.g * x.g.transpose() +
                     fxy * (cross + cross.transpose()));
}
template <int N>
inline Jet2<N> atan2(const Jet2<N>& y, double x) {
  return atan2(y, Jet2<N>(x, static_cast<int>(y.g.size())));
}
template <int N>
inline Jet2<N> atan2(double y, const Jet2<N>& x) {
  return atan2(Jet2<N>(y, static_cast<int>(x.g.size())), x);
}
template <int N>
inline Jet2<N> floor(const Jet2<N>& a) {
  return Jet2<N>(std::floor(a.v), static_cast<int>(a.g.size()));
}
template <int N>
inline bool isfinite(const Jet2<N>& a) {
  return std::isfinite(a.v);
}

/// Value of a double or of a jet.
inline double value_of(double x) { return x; }
template <int N>
inline double value_of(const Jet2<N>& x) {
  return x.v;
}

/// F, grad F and Hessian of a functor templated on the scalar type, by one jet evaluation.
/// `f` must accept `const Eigen::Matrix<Jet2<N>, N, 1>&` and return a Jet2<N>.
template <int N, typename Functor>
std::tuple<double, Vec<N>, Mat<N>> autodiff_hessian(const Functor& f, const Vec<N>& x) {
  const int dim = static_cast<int>(x.size());
  Eigen::Matrix<Jet2<N>, N, 1> xj(dim);
  for (int i = 0; i < dim; ++i) xj(i) = Jet2<N>::variable(x(i), i, dim);
  const Jet2<N> r = f(xj);
  if (r.g.size() == 0)  // the functor ignored x: constant
    return {r.v, Vec<N>::Zero(dim), Mat<N>::Zero(dim, dim)};
  return {r.v, r.g, r.h};
}

}  // namespace implicit

namespace Eigen {
// Lets Eigen matrices hold jets (e.g. Eigen::Matrix<Jet2<3>, 3, 1>).
template <int N>
struct NumTraits<implicit::Jet2<N>> : NumTraits<double> {
  using Real = implicit::Jet2<N>;
  using NonInteger = implicit::Jet2<N>;
  using Nested = implicit::Jet2<N>;
  using Literal = implicit::Jet2<N>;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 3,
    MulCost = 3
  };
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<implicit::Jet2<N>, double, BinaryOp> {
  using ReturnType = implicit::Jet2<N>;
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, implicit::Jet2<N>, BinaryOp> {
  using ReturnType = implicit::Jet2<N>;
};
}  // namespace Eigen
