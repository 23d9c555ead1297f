#pragma once
// The Wilson 95 % interval of a binomial fraction: with 20 runs a count is a coarse sample (2 of
// 20 and 6 of 20 are both compatible with a 15 % rate), so results compare intervals, not counts.
// Used by the mcl lost fraction and by the report's success and recovery rates.
#include <algorithm>
#include <array>
#include <cmath>

namespace implicit::experiments {

/// [low, high] for `count` successes of `n` trials (n > 0); the interval stays within [0, 1].
inline std::array<double, 2> wilson95(double count, double n) {
  const double z = 1.959963984540054, z2 = z * z;
  const double phat = count / n;
  const double centre = (phat + z2 / (2.0 * n)) / (1.0 + z2 / n);
  const double half = z * std::sqrt(phat * (1.0 - phat) / n + z2 / (4.0 * n * n)) / (1.0 + z2 / n);
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

}  // namespace implicit::experiments
