// `implicit arm`: path integral control of the two-link robot arm (paper §3.2, Figure 4).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments.hpp"
#include "implicit/core/parallel.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

void setup_arm(CLI::App& sub) {
  auto ctx = std::make_shared<RunContext>();
  auto settings = std::make_shared<ArmSettings>();
  auto allow_empty = std::make_shared<bool>(false);
  auto estimator = std::make_shared<std::string>("generic");  // parsed by parse_arm_estimator
  sub.add_option("--estimator", *estimator,
                 "generic: the library's path integral estimator on each joint as a "
                 "ControlProblem with partial noise; closed-form: each joint's path integral in "
                 "closed form, O(n) (the same controls to 1e-7, faster)")
      ->check(CLI::IsMember({"generic", "closed-form"}))
      ->capture_default_str();
  sub.add_flag("--allow-empty", *allow_empty,
               "Exit 0 even when a metric is not finite; a warning is printed either way");
  add_common_options(sub, *ctx);
  sub.callback([ctx, settings, allow_empty, estimator] {
    ThreadLimit limit(ctx->threads);
    settings->estimator = experiments::parse_arm_estimator(*estimator);
    const auto r = run_arm(*settings, *ctx);
    const auto check = [&] {
      require_scored(
          r, "arm",
          {"lqr_max_abs_diff", "final_angle_error_exact_rad", "final_angle_error_wrong_model_rad"},
          {}, *allow_empty);
    };
    if (ctx->json) {
      print_json(r);
      check();
      return;
    }
    fmt::print(
        "robot arm (target theta* = (1, -0.5) rad, tf = 2 s, {} estimator):\n"
        "  max |u_PI - u_LQR| = {:.2e}\n"
        "  |theta(tf) - theta*|: exact model {:.5f} rad, wrong model (m1 = 1.4) {:.5f} rad\n"
        "  {:.2f} s\n",
        *estimator, r["lqr_max_abs_diff"].get<double>(),
        r["final_angle_error_exact_rad"].get<double>(),
        r["final_angle_error_wrong_model_rad"].get<double>(), r["seconds"].get<double>());
    check();
  });
}

const Registrar register_arm{"arm", "Robot arm: path integral control = LQR, exact vs wrong model",
                             setup_arm};

}  // namespace
}  // namespace implicit::app
