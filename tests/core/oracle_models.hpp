#pragma once
// The closed-form oracle targets T1-T5 of the math spec §1.6, as models templated on the scalar
// (so one definition gives values for sampling and jets for derivatives), with their exact
// normalising constants and moments.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "implicit/core/jet.hpp"
#include "implicit/core/types.hpp"

namespace implicit::testing {

// Quartic constants: Z1 = integral of exp(-u^2/2 - u^4/4) du and its moments (spec §1.6).
inline constexpr double kZ1 = 1.9352478184967;
inline constexpr double kQuarticU2 = 0.46791991697367;
inline constexpr double kQuarticU4 = 0.53208008302633;

// T1: F = 1/2 (x-a)^T A (x-a) + c, A = [[4,1,.5],[1,3,.2],[.5,.2,2]], a = (1,-2,.5), c = 0.7.
inline Eigen::Matrix3d t1_matrix() {
  Eigen::Matrix3d a;
  a << 4, 1, 0.5, 1, 3, 0.2, 0.5, 0.2, 2;
  return a;
}
inline Eigen::Vector3d t1_centre() { return {1.0, -2.0, 0.5}; }
inline constexpr double kT1Offset = 0.7;
inline constexpr double kT1LogZ = 0.5276968601613241;

struct T1Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    using S = typename V::Scalar;
    const Eigen::Matrix3d a = t1_matrix();
    const Eigen::Vector3d c = t1_centre();
    S f(kT1Offset);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) f += 0.5 * a(i, j) * ((x(i) - c(i)) * (x(j) - c(j)));
    return f;
  }
};

// T2: F = x^2/2 + x^4/4 (m = 1); Z = Z1.
struct T2Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    const auto x2 = x(0) * x(0);
    return 0.5 * x2 + 0.25 * (x2 * x2);
  }
};

// T3: F = sum_{i=1}^6 (u_i^2/2 + u_i^4/4), u = A (x - c0), A = I + 0.3 11^T / 6,
// c0 = linspace(-1, 1, 6); Z = Z1^6 / det A with det A = 1.3.
inline constexpr double kT3Z = 40.408819866500;
inline Eigen::Matrix<double, 6, 1> t3_centre() {
  return Eigen::Matrix<double, 6, 1>::LinSpaced(6, -1.0, 1.0);
}
inline Eigen::Matrix<double, 6, 6> t3_matrix() {
  return Eigen::Matrix<double, 6, 6>::Identity() + Eigen::Matrix<double, 6, 6>::Constant(0.3 / 6.0);
}

struct T3Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    using S = typename V::Scalar;
    const Eigen::Matrix<double, 6, 1> c0 = t3_centre();
    S shift(0.0);  // 0.05 * sum_k (x_k - c0_k): the rank-one part of A (x - c0)
    for (int k = 0; k < 6; ++k) shift += 0.05 * (x(k) - c0(k));
    S f(0.0);
    for (int i = 0; i < 6; ++i) {
      const S u = (x(i) - c0(i)) + shift;
      const S u2 = u * u;
      f += 0.5 * u2 + 0.25 * (u2 * u2);
    }
    return f;
  }
};

// T4: F = x1^2/2 + x1^4/4 + 1/2 (x2 - 0.5 x1^2)^2 (a stabilised banana); Z = sqrt(2 pi) Z1.
inline constexpr double kT4Z = 4.850946900262;
inline constexpr double kT4X2 = 0.2339599585;
inline constexpr double kT4X2Squared = 1.1330200208;

struct T4Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    const auto x1s = x(0) * x(0);
    const auto r = x(1) - 0.5 * x1s;
    return 0.5 * x1s + 0.25 * (x1s * x1s) + 0.5 * (r * r);
  }
};

// T5: F = x1 - 4 log x1 + x2 + 2 log(1 + e^{-x2}), x1 > 0 (Gamma(5) x logistic); Z = 24,
// F = +inf for x1 <= 0. The softplus is written so that it neither overflows nor loses digits.
inline constexpr double kT5Z = 24.0;

struct T5Model {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    using S = typename V::Scalar;
    using std::exp;
    using std::log;
    using std::log1p;
    if (!(x(0) > 0.0)) return S(std::numeric_limits<double>::infinity());
    // x2 + 2 log(1 + e^{-x2}) = |x2| + 2 log(1 + e^{-|x2|}) (the logistic density is symmetric).
    const S a = x(1) < 0.0 ? S(-x(1)) : S(x(1));
    return x(0) - 4.0 * log(x(0)) + a + 2.0 * log1p(exp(-a));
  }
};

}  // namespace implicit::testing
