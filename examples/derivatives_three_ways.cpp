// One model, three derivative strategies: analytic, automatic (second-order jets) and numeric
// (central differences), plus check_derivatives() to verify hand-written derivatives.
//
// The model: a robot at x in R^2 with a Gaussian prior N(x_prior, I) measures its range to a
// landmark m with noise sd sigma. The negative log posterior (up to a constant) is
//   F(x) = 1/2 |x - x_prior|^2 + 1/2 (|x - m| - r)^2 / sigma^2.
//
//   ./example_derivatives_three_ways

#include <cmath>
#include <cstdio>

#include "implicit/implicit.hpp"

namespace {

const Eigen::Vector2d kPrior(0.5, -0.2);
const Eigen::Vector2d kLandmark(4.0, 3.0);
constexpr double kRange = 5.2;
constexpr double kSigma = 0.3;

// 1. The model templated on the scalar: doubles for values, jets for exact derivatives.
struct RangeModel {
  template <typename V>
  typename V::Scalar operator()(const V& x) const {
    using std::sqrt;
    const auto p0 = x(0) - kPrior(0), p1 = x(1) - kPrior(1);
    const auto d0 = x(0) - kLandmark(0), d1 = x(1) - kLandmark(1);
    const auto e = sqrt(d0 * d0 + d1 * d1) - kRange;
    return 0.5 * (p0 * p0 + p1 * p1) + 0.5 * (e * e) / (kSigma * kSigma);
  }
};

// 2. The same F with hand-derived derivatives (d = x - m, rho = |d|, e = rho - r):
//    grad = (x - x_prior) + (e / sigma^2) d / rho
//    H    = I + (1 / sigma^2) [d d^T / rho^2 + e (I / rho - d d^T / rho^3)]
double range_analytic(const Eigen::Vector2d& x, Eigen::Vector2d* grad, Eigen::Matrix2d* hess) {
  const Eigen::Vector2d d = x - kLandmark;
  const double rho = d.norm(), e = rho - kRange, s2 = kSigma * kSigma;
  if (grad) *grad = (x - kPrior) + (e / s2) * d / rho;
  if (hess) {
    const Eigen::Matrix2d ddt = d * d.transpose();
    *hess =
        Eigen::Matrix2d::Identity() +
        (ddt / (rho * rho) + e * (Eigen::Matrix2d::Identity() / rho - ddt / (rho * rho * rho))) /
            s2;
  }
  return 0.5 * (x - kPrior).squaredNorm() + 0.5 * e * e / s2;
}

}  // namespace

int main() {
  const auto analytic = implicit::make_analytic_target<2>(range_analytic);
  const auto automatic = implicit::make_autodiff_target<2>(RangeModel{});
  const auto numeric =
      implicit::make_numeric_target<2>([](const Eigen::Vector2d& x) { return RangeModel{}(x); });

  const Eigen::Vector2d x(0.3, 0.1);
  Eigen::Vector2d g[3];
  Eigen::Matrix2d h[3];
  const double f[3] = {analytic.evaluate(x, &g[0], &h[0]), automatic.evaluate(x, &g[1], &h[1]),
                       numeric.evaluate(x, &g[2], &h[2])};
  const char* names[3] = {"analytic", "automatic", "numeric"};
  for (int k = 0; k < 3; ++k)
    std::printf("%-9s F = %.12f  grad = (%.10f, %.10f)  H = [%.8f %.8f; %.8f %.8f]\n", names[k],
                f[k], g[k](0), g[k](1), h[k](0, 0), h[k](0, 1), h[k](1, 0), h[k](1, 1));
  std::printf("numeric vs automatic: max gradient error %.2e, max Hessian error %.2e\n",
              (g[2] - g[1]).cwiseAbs().maxCoeff(), (h[2] - h[1]).cwiseAbs().maxCoeff());

  // check_derivatives compares a target's derivatives with automatic ones of the same model.
  const implicit::DerivativeCheck ok = implicit::check_derivatives(analytic, RangeModel{}, x);
  std::printf("check analytic:  %s -> %s\n", ok.describe().c_str(), ok.ok(1e-10) ? "ok" : "WRONG");

  // A typical mistake (dropping the e-term of the Hessian) is caught and located.
  const auto wrong = implicit::make_analytic_target<2>(
      [](const Eigen::Vector2d& y, Eigen::Vector2d* gr, Eigen::Matrix2d* he) {
        const double value = range_analytic(y, gr, he);
        if (he) {
          const Eigen::Vector2d d = y - kLandmark;
          *he = Eigen::Matrix2d::Identity() + d * d.transpose() / d.squaredNorm() / 0.09;
        }
        return value;
      });
  const implicit::DerivativeCheck bad = implicit::check_derivatives(wrong, RangeModel{}, x);
  std::printf("check wrong one: %s -> %s\n", bad.describe().c_str(),
              bad.ok(1e-10) ? "ok" : "WRONG");

  // All three drive the same minimiser to the same mode.
  const auto r_a = implicit::minimize(analytic, kPrior);
  const auto r_n = implicit::minimize(numeric, kPrior);
  std::printf("mode (analytic) = (%.10f, %.10f), status %s\n", r_a.x(0), r_a.x(1),
              std::string(implicit::to_string(r_a.status)).c_str());
  std::printf("mode (numeric)  = (%.10f, %.10f), status %s\n", r_n.x(0), r_n.x(1),
              std::string(implicit::to_string(r_n.status)).c_str());
  return ok.ok(1e-10) && !bad.ok(1e-10) ? 0 : 1;
}
