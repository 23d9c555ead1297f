// The arm experiment (Figure 4) on both estimators: the generic one (each joint a ControlProblem
// with partial noise, the default) and the closed form give the same closed loop up to the
// rounding of the generic control's central difference (spec §2.5.2: below 1e-7 in u).
#include <gtest/gtest.h>

#include "experiments/control.hpp"
#include "implicit/core/error.hpp"

using namespace implicit::experiments;

TEST(ArmExperiment, GenericAndClosedFormGiveTheSameClosedLoop) {
  const RunContext ctx;
  ArmSettings generic, closed;
  closed.estimator = implicit::control::ArmController::kClosedForm;
  // The experiment runs on the library's estimator.
  EXPECT_EQ(generic.estimator, implicit::control::ArmController::kGeneric);
  const auto g = run_arm(generic, ctx), c = run_arm(closed, ctx);
  EXPECT_EQ(g["estimator"], "generic");
  EXPECT_LT(g["lqr_max_abs_diff"].get<double>(), 1e-7);
  EXPECT_LT(c["lqr_max_abs_diff"].get<double>(), 1e-9);
  for (const char* key : {"final_state_exact", "final_state_wrong_model", "initial_torque_exact"})
    for (std::size_t i = 0; i < g[key].size(); ++i)
      EXPECT_NEAR(g[key][i].get<double>(), c[key][i].get<double>(), 1e-7) << key << " " << i;
}

TEST(ArmExperiment, RefusesAnUnknownEstimator) {
  try {
    parse_arm_estimator("fast");
    ADD_FAILURE() << "no exception";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "arm --estimator: expected 'closed-form' or 'generic', got 'fast'");
  }
  EXPECT_EQ(parse_arm_estimator("closed-form"), implicit::control::ArmController::kClosedForm);
  EXPECT_EQ(name_of(parse_arm_estimator("generic")), "generic");
}
