// The double slit of path integral control (paper §3.1, Table 1, Figures 1-2): plain Monte
// Carlo fails, implicit sampling with one constrained minimum per slit works.
//
//   ./example_double_slit

#include <cstdio>

#include "implicit/control/double_slit.hpp"

namespace ic = implicit::control;

int main() {
  const ic::DoubleSlit slit;  // Table 1: slits [-6,-4] and [6,8] at t1 = 1, tf = 2, x(0) = 1

  // Plain Monte Carlo: random walks from x(0) almost never pass (P ~ 6e-7).
  const auto mc = slit.plain_monte_carlo(1.0, 0, 100000, 1);
  std::printf("plain Monte Carlo: %d of %d walks pass the wall\n", mc.passed, mc.paths);

  // Implicit sampling at (x, t) = (1, 0): the exact control and two estimators with M = 50.
  std::printf("exact u(1, 0) = %.6f\n", slit.exact_control(1.0, 0.0));
  for (auto est : {ic::SlitEstimator::kFrozenWall, ic::SlitEstimator::kPaper}) {
    const auto e = slit.estimate_control(1.0, 0, 50, est, {.seed = 3});
    std::printf("  %-9s u = %.6f (ESS %.1f, %d of %d samples passed)\n",
                std::string(ic::to_string(est)).c_str(), e.u, e.ess, e.passed, e.samples);
  }

  // One closed-loop run (spec §2.4.6): exact and estimated controllers share the noise.
  const auto run = ic::simulate_slit_run(slit, 50, ic::SlitEstimator::kFrozenWall, 1, 0);
  std::printf("closed loop: e_x = %.2f %%, e_u = %.2f %%, x(t1) = %.3f (exact control: %.3f)\n",
              100 * run.error_x, 100 * run.error_u, run.x_estimate(slit.wall_step()),
              run.x_exact(slit.wall_step()));
  return 0;
}
