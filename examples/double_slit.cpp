// The double slit of path integral control (paper §3.1, Table 1, Figures 1-2): plain Monte
// Carlo fails, implicit sampling with one constrained minimum per slit works. The last part
// solves the same problem through the generic ControlProblem with a HardWall, the way you would
// describe your own problem with walls (double_slit_problem builds it from the parameters:
// G = 1, Q Q^T = sigma, R = r, final cost x^2 / 2, the slits as the wall's openings).
//
//   ./example_double_slit

#include <cmath>
#include <cstdio>

#include "implicit/control/double_slit.hpp"
#include "implicit/control/double_slit_problem.hpp"
#include "implicit/control/path_integral.hpp"

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

  // The generic route: the same problem as a ControlProblem with a HardWall at t1 whose
  // openings are the slits (double_slit_problem.hpp). The estimator finds one constrained
  // minimum per opening and samples their mixture; frozen-wall FD for the control.
  const auto problem = ic::double_slit_problem(slit.parameters());
  const auto c = ic::estimate_control(problem, implicit::Vec<1>(1.0), 0,
                                      {.samples = 50, .fd_step = 1e-3}, {.seed = 3});
  std::printf("generic HardWall: u = %.6f, log psi = %.4f (exact %.4f), ESS %.1f, %d of %d hit\n",
              c.u(0), c.psi.log_psi, slit.exact_log_psi(1.0, 0.0), c.psi.ess, c.psi.wall_hits,
              c.psi.samples);
  for (const auto& m : c.psi.modes)
    std::printf("  opening %d: mixture weight %.4f, path at the wall %.2f\n", m.openings[0],
                std::exp(m.log_weight), m.wall_values[0]);
  return 0;
}
