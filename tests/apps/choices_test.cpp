// The settings' choices (experiments/choices.hpp): every name parses to its enum and back, and a
// text that is no name is refused with the message the command line's and Python's bad-input
// rows show.
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "experiments/choices.hpp"
#include "implicit/core/error.hpp"

namespace {

using namespace implicit::experiments;

template <typename Parse>
void expect_round_trip(Parse parse, const std::vector<std::string_view>& names) {
  for (const std::string_view n : names) EXPECT_EQ(name_of(parse(n)), n);
}

template <typename Parse>
std::string refusal(Parse parse, std::string_view text) {
  try {
    parse(text);
  } catch (const implicit::InvalidArgument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Choices, EveryNameParsesToItsEnumAndBack) {
  expect_round_trip(parse_slit_mode, {"paper", "corrected", "plain"});
  expect_round_trip(parse_slit_estimator, {"generic", "wall-space"});
  expect_round_trip(parse_arm_estimator, {"generic", "closed-form"});
  expect_round_trip(parse_noise_config, {"A", "B"});
  expect_round_trip(parse_implicit_map, {"linear", "random"});
  expect_round_trip(parse_sigma2, {"variance", "std"});
  expect_round_trip(parse_mcl_truth, {"gps", "reference"});
  expect_round_trip(parse_slam_truth, {"paper", "consistent"});
  EXPECT_EQ(parse_slit_mode("corrected"), implicit::control::SlitEstimator::kFrozenWall);
  EXPECT_EQ(parse_noise_config("B"), NoiseConfig::kB);
  EXPECT_EQ(parse_slam_truth("consistent"), implicit::slam::TruthMode::kConsistent);
}

TEST(Choices, OtherTextIsRefusedNamingTheFlagAndTheNames) {
  EXPECT_EQ(refusal(parse_slit_mode, "Paper"),
            "slit mode: expected 'paper', 'corrected' or 'plain', got 'Paper'");
  EXPECT_EQ(refusal(parse_slit_estimator, "fast"),
            "slit --estimator: expected 'wall-space' or 'generic', got 'fast'");
  EXPECT_EQ(refusal(parse_arm_estimator, ""),
            "arm --estimator: expected 'closed-form' or 'generic', got ''");
  EXPECT_EQ(refusal(parse_noise_config, "C"), "mcl --config: expected 'A' or 'B', got 'C'");
  EXPECT_EQ(refusal(parse_implicit_map, "cubic"),
            "mcl --map: expected 'linear' or 'random', got 'cubic'");
  EXPECT_EQ(refusal(parse_sigma2, "var"), "mcl --sigma2: expected 'variance' or 'std', got 'var'");
  EXPECT_EQ(refusal(parse_mcl_truth, "GPS"),
            "mcl --truth: expected 'gps' or 'reference', got 'GPS'");
  EXPECT_EQ(refusal(parse_slam_truth, "log"), "--truth: expected paper|consistent, got 'log'");
}

}  // namespace
