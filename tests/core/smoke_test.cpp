#include <gtest/gtest.h>

#include "implicit/implicit.hpp"

TEST(Smoke, GaussianEqualWeights) {
  auto t = implicit::make_autodiff_target<3>([](const auto& x) {
    using T = std::decay_t<decltype(x(0))>;
    T s = 0.5 * x(0) * x(0) + x(1) * x(1) + 2.0 * x(2) * x(2) + 0.3 * x(0) * x(1);
    return s;
  });
  auto set = implicit::sample(t, Eigen::Vector3d(1, 2, 3), 1000, {7});
  EXPECT_NEAR(set.ess, 1000.0, 1e-6);
}
