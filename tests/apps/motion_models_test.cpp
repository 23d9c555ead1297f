// The registry of motion models (experiments/motion_models.hpp): lookups, registrations refused
// with their reason, the declaration and noise a model is built with, and docs/formats.md's
// table drawn from it.
#include "experiments/motion_models.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <type_traits>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "markdown_table.hpp"

namespace implicit::experiments {
namespace {

MotionModelEntry valid_entry(std::string name) {
  MotionModelEntry e;
  e.name = std::move(name);
  e.keys = {{"dt", "control period [s]", 0.2}};
  e.default_noise = {{0.1, 0.05}, {0.02, 0.02, 0.01}};
  e.build = [](const robot::VehicleDeclaration& v, const MotionNoise& noise) {
    robot::UnicycleParams p;
    p.dt = *v.parameter("dt");
    p.control_std = Vec<2>(noise.control_sd[0], noise.control_sd[1]);
    p.state_std = Vec<3>(noise.state_sd[0], noise.state_sd[1], noise.state_sd[2]);
    return robot::AnyMotionModel(robot::UnicycleModel(p));
  };
  return e;
}

TEST(MotionModels, TheBuiltInsComeFirstAndUnknownNamesAreRefusedWithTheChoices) {
  const auto names = motion_model_names();
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0], "ute");
  EXPECT_EQ(names[1], "unicycle");
  EXPECT_EQ(motion_model("unicycle", "mcl --model").controls, "u1 = v [m/s], u2 = omega [rad/s]");
  try {
    (void)motion_model("tank", "mcl --model");
    FAIL() << "an unknown model was found";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("mcl --model: expected one of 'ute', 'unicycle'"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("got 'tank'"), std::string::npos) << e.what();
  }
}

TEST(MotionModels, ARegistrationIsRefusedWithItsReason) {
  const auto refused = [](MotionModelEntry e, const std::string& reason) {
    try {
      register_motion_model(std::move(e));
      ADD_FAILURE() << "registered, expected: " << reason;
    } catch (const InvalidArgument& err) {
      EXPECT_NE(std::string(err.what()).find(reason), std::string::npos) << err.what();
    }
  };
  refused(valid_entry("ute"), "the name 'ute' is taken");
  refused(valid_entry("two words"), "expected a name without blanks");
  refused(valid_entry("a=b"), "expected a name without blanks");
  MotionModelEntry no_build = valid_entry("no-build");
  no_build.build = nullptr;
  refused(no_build, "expected a build function");
  MotionModelEntry no_dt = valid_entry("no-dt");
  no_dt.keys = {{"L", "wheelbase [m]", 1.0}};
  refused(no_dt, "expected the `vehicle` key dt");
  MotionModelEntry bad_noise = valid_entry("bad-noise");
  bad_noise.default_noise.state_sd = {0.1};
  refused(bad_noise, "expected a default noise of 2 control and 3 state sds");
  for (const char* name : {"two words", "a=b", "no-build", "no-dt", "bad-noise"})
    EXPECT_THROW((void)motion_model(name, "test"), InvalidArgument) << name;
}

TEST(MotionModels, AModelIsBuiltFromTheFullDeclarationAndTheNoiseFilledIn) {
  register_motion_model(valid_entry("test-unicycle"));
  const MotionModelEntry& e = motion_model("test-unicycle", "test");
  EXPECT_EQ(motion_model_names().back(), "test-unicycle");
  // A declaration without dt gets the default; noise flags left empty get the defaults.
  const robot::AnyMotionModel m = make_motion_model(e, {}, {});
  ASSERT_NE(m.target<robot::UnicycleModel>(), nullptr);
  EXPECT_EQ(m.dt(), 0.2);
  EXPECT_EQ(m.target<robot::UnicycleModel>()->params().control_std, Vec<2>(0.1, 0.05));
  EXPECT_EQ(m.target<robot::UteModel>(), nullptr);
  const robot::AnyMotionModel n =
      make_motion_model(e, {"test-unicycle", {{"dt", 0.5}}}, {{0.3, 0.4}, {}});
  EXPECT_EQ(n.dt(), 0.5);
  EXPECT_EQ(n.target<robot::UnicycleModel>()->params().control_std, Vec<2>(0.3, 0.4));
  EXPECT_EQ(n.target<robot::UnicycleModel>()->params().state_std, Vec<3>(0.02, 0.02, 0.01));
  EXPECT_THROW((void)make_motion_model(e, {}, {{0.3}, {}}), InvalidArgument);
  // full_declaration: the model's keys in its order, then what else was declared (for the build
  // to refuse).
  const robot::VehicleDeclaration d =
      full_declaration(motion_model("ute", "test"), {"ute", {{"x", 1.0}, {"L", 3.0}}});
  ASSERT_EQ(d.parameters.size(), 6u);
  EXPECT_EQ(d.parameters[0].first, "dt");
  EXPECT_EQ(d.parameters[1], (std::pair<std::string, double>{"L", 3.0}));
  EXPECT_EQ(d.parameters[5].first, "x");
  EXPECT_THROW((void)make_motion_model(motion_model("ute", "test"), d, {}), InvalidArgument);
  // The built-ins run through their own types.
  const robot::AnyMotionModel ute = make_motion_model(motion_model("ute", "test"), {}, {});
  EXPECT_EQ(
      visit_motion_model(ute,
                         [](const auto& model) {
                           return std::is_same_v<std::decay_t<decltype(model)>, robot::UteModel>;
                         }),
      true);
}

/// "| `name` | controls | `k` meaning (default); ... | description |" for each built-in.
std::string table_row(const MotionModelEntry& e) {
  std::string keys;
  for (const VehicleKey& k : e.keys)
    keys +=
        fmt::format("{}`{}` {} ({})", keys.empty() ? "" : "; ", k.name, k.meaning, k.default_value);
  return fmt::format("| `{}` | {} | {} | {} |", e.name, e.controls, keys, e.description);
}

TEST(MotionModels, TheFormatsTableListsEveryBuiltInModelAsTheRegistryDoes) {
  const std::vector<std::string> table = implicit::test::markdown_table_rows(
      "docs/formats.md", "| model | controls | `vehicle` keys (default) | robot |");
  ASSERT_FALSE(table.empty()) << "docs/formats.md: no table of motion models";
  const std::set<std::string> rows(table.begin(), table.end());
  std::set<std::string> expected;
  for (const char* name : {"ute", "unicycle"})
    expected.insert(table_row(motion_model(name, "test")));
  EXPECT_EQ(rows, expected);
}

}  // namespace
}  // namespace implicit::experiments
