#pragma once
// Counts in printed summaries: "1 run", "20 runs" (never "1 runs").

#include <string>

#include <fmt/format.h>

namespace implicit::experiments {

/// `n` and the noun, singular for exactly one, else plural: counted(1, "run", "runs") is
/// "1 run", counted(0, "data set", "data sets") is "0 data sets".
inline std::string counted(long long n, const std::string& singular, const std::string& plural) {
  return fmt::format("{} {}", n, n == 1 ? singular : plural);
}

}  // namespace implicit::experiments
