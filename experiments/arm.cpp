// Robot arm experiment (paper §3.2, Figure 4; spec §2.5): path integral control of a two-link
// arm, with the exact model and with the controller's wrong model (m1 = 1.4), on the nonlinear
// plant (RK4, 10 substeps, no noise), and the check that path integral control equals LQR.
#include <chrono>

#include <fmt/format.h>
#include <fmt/os.h>

#include "experiments/control.hpp"
#include "implicit/control/robot_arm.hpp"
#include "implicit/core/error.hpp"

namespace implicit::experiments {

nlohmann::json run_arm(const ArmSettings& s, const RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  const control::ArmController controller = s.estimator;
  const control::ArmProblem problem;   // spec §2.5.4
  const control::ArmParameters plant;  // Table 3
  control::ArmParameters wrong = plant;
  wrong.m1 = 1.4;  // the controller believes the arm carries a payload
  const auto exact = control::simulate_arm(problem, plant, plant, 10, controller);
  const auto biased = control::simulate_arm(problem, plant, wrong, 10, controller);
  control::ArmProblem semi = problem;
  semi.scheme = control::ArmScheme::kSemiImplicit;
  const auto semi_sim = control::simulate_arm(semi, plant, plant);

  if (!ctx.out_dir.empty()) {
    OutputFile out(ctx.csv_path("figure4_arm.csv"));
    out.print(
        "t,theta1_exact,theta2_exact,dtheta1_exact,dtheta2_exact,tau1_exact,tau2_exact,"
        "theta1_wrong,theta2_wrong,dtheta1_wrong,dtheta2_wrong,tau1_wrong,tau2_wrong\n");
    for (std::size_t k = 0; k < exact.t.size(); ++k) {
      out.print("{:.4f}", exact.t[k]);
      for (const auto* sim : {&exact, &biased}) {
        const auto& x = sim->x[k];
        out.print(",{:.10f},{:.10f},{:.10f},{:.10f}", x(0), x(1), x(2), x(3));
        if (k < sim->tau.size())
          out.print(",{:.10f},{:.10f}", sim->tau[k](0), sim->tau[k](1));
        else
          out.print(",nan,nan");
      }
      out.print("\n");
    }
    out.commit();
  }
  auto vec = [](const auto& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {
      {"estimator", name_of(s.estimator)},
      {"lqr_max_abs_diff", std::max(exact.lqr_max_abs_diff, biased.lqr_max_abs_diff)},
      {"lqr_max_abs_diff_semi_implicit", semi_sim.lqr_max_abs_diff},
      {"final_angle_error_exact_rad", exact.final_angle_error},
      {"final_angle_error_wrong_model_rad", biased.final_angle_error},
      {"final_state_exact", vec(exact.x.back())},
      {"final_state_wrong_model", vec(biased.x.back())},
      {"initial_torque_exact", vec(exact.tau.front())},
      {"initial_torque_wrong_model", vec(biased.tau.front())},
      {"target_rad", vec(problem.target)},
      {"seed", ctx.seed},
      {"seconds", seconds},
  };
}

}  // namespace implicit::experiments
