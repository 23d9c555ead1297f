// The settings' choices (experiments/choices.hpp): every name parses to its enum and back, and a
// text that is no name is refused with the message the command line's and Python's bad-input
// rows show.
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "experiments/choices.hpp"
#include "experiments/laser_mcl.hpp"
#include "implicit/core/error.hpp"
#include "implicit/da/filters.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "implicit/slam/slam_filter.hpp"
#include "markdown_table.hpp"

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

TEST(Choices, EveryListedMethodParsesWhereTheRunParsesIt) {
  for (const Choice& c : mcl_methods().choices)
    EXPECT_NO_THROW((void)parse_proposal(c.name)) << c.name;
  for (const Choice& c : laser_models().choices)
    EXPECT_EQ(to_string(parse_laser_model(c.name)), c.name);
  for (const Choice& c : landmark_slam_methods().choices)
    EXPECT_NO_THROW((void)implicit::slam::parse_slam_method(c.name)) << c.name;
  for (const Choice& c : grid_slam_methods().choices)
    EXPECT_EQ(implicit::slam::to_string(implicit::slam::parse_grid_proposal(c.name)), c.name);
  // implicit-smoother runs da::ImplicitSmoother (experiments/da.cpp); the others are the
  // filters of da::parse_method.
  for (const Choice& c : da_methods().choices) {
    if (c.name != "implicit-smoother") {
      EXPECT_NO_THROW((void)implicit::da::parse_method(c.name)) << c.name;
    }
  }
  // And what the runs parse is listed: a method the parsers know but the list does not would be
  // refused by the tool's check.
  EXPECT_THROW((void)implicit::da::parse_method("no-such-method"), implicit::InvalidArgument);
  EXPECT_EQ(da_methods().names().size(), 5u);
  EXPECT_EQ(landmark_slam_methods().names().size(), 5u);
}

TEST(Choices, ACheckNamesTheSettingAndEveryChoice) {
  EXPECT_EQ(refusal([](std::string_view t) { return mcl_methods().check(t); }, "x"),
            "mcl --method: expected 'standard' or 'implicit', got 'x'");
  EXPECT_EQ(refusal([](std::string_view t) { return da_methods().check(t, "method"); }, "pf"),
            "method: expected 'bootstrap', 'implicit', 'enkf', 'etkf' or 'implicit-smoother', "
            "got 'pf'");
  EXPECT_EQ(mcl_methods().check("implicit"), "implicit");
  EXPECT_EQ(laser_models().help(),
            "likelihood-field: distances to the nearest obstacle (both proposals); beam: ray "
            "casting (the bootstrap proposal only)");
}

TEST(Choices, TheTableOfCliMdIsTheListOfChoices) {
  const std::vector<std::string> rows =
      implicit::test::markdown_table_rows("docs/cli.md", "| setting | choice | meaning |");
  ASSERT_FALSE(rows.empty()) << "docs/cli.md: no table of choices";
  std::vector<std::string> expected;
  for (const ChoiceSet* set : choice_sets())
    for (const Choice& c : set->choices)
      expected.push_back(fmt::format("| `{}` | `{}` | {} |", set->setting, c.name, c.meaning));
  EXPECT_EQ(rows, expected);
}

}  // namespace
