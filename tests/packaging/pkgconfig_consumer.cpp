// A downstream program built with `pkg-config --cflags --libs implicit` against the installed
// library: samples a 1-D Gaussian, whose log Z is known exactly.
#include <implicit/core/implicit_sampler.hpp>

#include <cmath>

int main() {
  auto target = implicit::make_analytic_target<1>([](const Eigen::Matrix<double, 1, 1>& x,
                                                     Eigen::Matrix<double, 1, 1>* g,
                                                     Eigen::Matrix<double, 1, 1>* h) {
    if (g) (*g)(0) = x(0);
    if (h) (*h)(0, 0) = 1.0;
    return 0.5 * x(0) * x(0);
  });
  const auto result =
      implicit::sample(target, Eigen::Matrix<double, 1, 1>::Zero(), 100, implicit::StreamKey{7});
  return std::abs(result.log_Z - 0.5 * std::log(2.0 * M_PI)) < 1e-10 ? 0 : 1;
}
