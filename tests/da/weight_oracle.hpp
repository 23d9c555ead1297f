#pragma once
// The exact-weight oracle of the implicit filter tests: on a linear-Gaussian problem every
// member's weight is its parent's closed-form likelihood p(y | x'), whatever its reference
// variable, so the normalised weights equal the normalised exp(log p) to round-off (1e-9
// relative).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

namespace implicit::da::test {

inline void expect_weights_proportional_to(std::span<const double> weights,
                                           const std::vector<double>& log_p,
                                           const std::string& what) {
  ASSERT_EQ(weights.size(), log_p.size()) << what;
  const double top = *std::max_element(log_p.begin(), log_p.end());
  double total = 0.0;
  for (double l : log_p) total += std::exp(l - top);
  for (std::size_t j = 0; j < log_p.size(); ++j)
    EXPECT_NEAR(weights[j] * total / std::exp(log_p[j] - top), 1.0, 1e-9) << what << ", j = " << j;
}

}  // namespace implicit::da::test
