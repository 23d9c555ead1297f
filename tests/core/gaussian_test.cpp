// core/gaussian.hpp: the Gaussian normaliser written once. The density is checked against one
// built from its covariance with Eigen (determinant and inverse, not a Cholesky factor) and
// against a quadrature of its mass; a scan of the sources keeps the constant from being written
// by hand again.
#include "implicit/core/gaussian.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace implicit {
namespace {

TEST(Gaussian, LogDensityIsTheDensityOfItsCovariance) {
  Mat<3> a;
  a << 1.3, 0.2, -0.4, 0.0, 0.7, 0.5, 0.3, -0.1, 2.1;
  const Mat<3> sigma = a * a.transpose() + 0.1 * Mat<3>::Identity();
  const Vec<3> mu(0.5, -1.0, 2.0), x(1.1, -0.2, 1.4);
  const Vec<3> d = x - mu;
  const double r2 = d.dot(sigma.inverse() * d);
  // The textbook form: exp(-r^2 / 2) / sqrt(det(2 pi Sigma)).
  const double direct = std::exp(-0.5 * r2) / std::sqrt((2.0 * kPi * sigma).determinant());
  const Mat<3> l = sigma.llt().matrixL();
  const double log_det_l = l.diagonal().array().log().sum();
  EXPECT_NEAR(gaussian_log_density(3, log_det_l, r2), std::log(direct), 1e-12);
  EXPECT_NEAR(gaussian_log_normaliser(3, log_det_l),
              0.5 * std::log((2.0 * kPi * sigma).determinant()), 1e-12);
  // One dimension: Z = sqrt(2 pi) sd, and log Z is the log-normaliser of log det L = log sd.
  EXPECT_NEAR(gaussian_normaliser(0.3), std::sqrt(2.0 * kPi * 0.09), 1e-15);
  EXPECT_NEAR(std::log(gaussian_normaliser(0.3)), gaussian_log_normaliser(1, std::log(0.3)), 1e-15);
  // One dimension, unit variance, at 0: 1 / sqrt(2 pi).
  EXPECT_NEAR(std::exp(gaussian_log_density(1, 0.0, 0.0)), 0.3989422804014327, 1e-15);
}

TEST(Gaussian, TheDensityIntegratesToOne) {
  // A 2-D Gaussian with sd 0.7 and 1.9 and correlation 0.6, by the midpoint rule over +-10 sd:
  // the rule's error on a smooth, rapidly decaying integrand is far below 1e-9.
  const double s1 = 0.7, s2 = 1.9, rho = 0.6;
  Mat<2> sigma;
  sigma << s1 * s1, rho * s1 * s2, rho * s1 * s2, s2 * s2;
  const Mat<2> information = sigma.inverse();
  const double log_det_l = 0.5 * std::log(sigma.determinant());
  const int n = 800;
  const double h1 = 20.0 * s1 / n, h2 = 20.0 * s2 / n;
  double mass = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Vec<2> x(-10.0 * s1 + (i + 0.5) * h1, -10.0 * s2 + (j + 0.5) * h2);
      mass += std::exp(gaussian_log_density(2, log_det_l, x.dot(information * x))) * h1 * h2;
    }
  EXPECT_NEAR(mass, 1.0, 1e-9);
}

/// "file:line: text" for every line of code (comments left out) in the library, the tools, the
/// examples and the bindings that spells out log(2 pi) or sqrt(2 pi) itself.
std::vector<std::string> hand_written_normalisers() {
  const std::filesystem::path root(IMPLICIT_SOURCE_DIR);
  const std::regex pattern(
      R"(kLog2Pi|(log|sqrt)\(\s*2(\.0)?\s*\*\s*(kPi|M_PI|std::numbers::pi|pi)\b)");
  std::vector<std::string> found;
  for (const char* dir :
       {"include", "src", "apps", "experiments", "examples", "bench", "python", "fuzz"}) {
    if (!std::filesystem::is_directory(root / dir)) continue;
    for (const auto& e : std::filesystem::recursive_directory_iterator(root / dir)) {
      const auto ext = e.path().extension();
      if (!e.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
      const std::string name = std::filesystem::relative(e.path(), root).string();
      if (name == "include/implicit/core/gaussian.hpp" || name == "include/implicit/core/types.hpp")
        continue;
      std::ifstream in(e.path());
      std::string line;
      for (int number = 1; std::getline(in, line); ++number) {
        const std::string code = line.substr(0, line.find("//"));
        if (std::regex_search(code, pattern))
          found.push_back(name + ":" + std::to_string(number) + ": " + line);
      }
    }
  }
  return found;
}

TEST(Gaussian, NoSourceWritesTheNormaliserByHand) {
  for (const auto& f : hand_written_normalisers())
    ADD_FAILURE() << f << ": use gaussian_log_normaliser or gaussian_log_density "
                  << "(implicit/core/gaussian.hpp)";
}

}  // namespace
}  // namespace implicit
