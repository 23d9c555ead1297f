// Path integral control of your own problem: a planar robot pushed by wind must reach a goal
// while avoiding a soft obstacle. Copy this file and change the Model and the ControlSpec.
//
//   dx = (wind + u) dt + sqrt(sigma) dW,   cost E[ 5 |x(tf) - goal|^2 + integral (r|u|^2/2 + V) ]
//   V(x) = 20 exp(-|x - obstacle|^2 / (2 * 0.3^2))   (a bump to walk around)
//
//   ./example_custom_control                # log psi by two estimators, then a closed-loop run
//   ./example_custom_control --map random   # the same with the random map of implicit sampling
//
// The second part adds a hard wall (a gate at t = 1 with two openings): the estimator then finds
// one constrained minimum per opening and samples a mixture over them.

#include <cmath>
#include <cstdio>
#include <string_view>

#include "implicit/control/path_integral.hpp"
#include "implicit/core/rng.hpp"

namespace ic = implicit::control;

// The model: drift f(x, t), running cost V(x, t) and final cost Phi(x), each templated on the
// scalar T so that the library can differentiate them automatically (T = double or a jet).
struct WindyRobot {
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double /*t*/) const {
    Eigen::Matrix<T, 2, 1> wind;
    wind << x(0) * 0.0 + 0.3, x(1) * 0.0;  // constant wind along +x
    return wind;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double /*t*/) const {
    using std::exp;
    const T dx = x(0) - 1.0, dy = x(1) - 0.0;
    return 20.0 * exp(-(dx * dx + dy * dy) / (2.0 * 0.09));
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    const T dx = x(0) - 2.0, dy = x(1);
    return 5.0 * (dx * dx + dy * dy);
  }
};

int main(int argc, char** argv) {
  ic::SamplingMap map = ic::SamplingMap::kLinear;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    const std::string_view v = i + 1 < argc ? argv[i + 1] : "";
    if (a == "--map" && (v == "linear" || v == "random")) {
      map = v == "linear" ? ic::SamplingMap::kLinear : ic::SamplingMap::kRandom;
      ++i;
    } else {
      std::fprintf(stderr, "usage: %s [--map linear|random]; got '%s'\n", argv[0], argv[i]);
      return 2;
    }
  }
  // Linear parts: G = I (the control acts on both axes), noise covariance Q Q^T = sigma I,
  // control cost R = r I. Condition (8) then holds with gamma = sigma r; the constructor checks
  // it and throws a message naming the mismatching entry if you choose R and Q inconsistently.
  ic::ControlSpec<2, 2> spec;
  spec.G.setIdentity();
  spec.noise_covariance = 0.05 * implicit::Mat<2>::Identity();
  spec.control_cost = 2.0 * implicit::Mat<2>::Identity();
  spec.horizon = 2.0;
  spec.dt = 0.05;
  const ic::ControlProblem problem(WindyRobot{}, spec);
  std::printf("gamma = %.3f, %d steps\n", problem.gamma(), problem.num_steps());

  // log psi at the start by implicit sampling (50 samples) and plain Monte Carlo (5000 paths).
  // Plain Monte Carlo rarely samples the low-cost paths (around the bump, into the goal), so its
  // ESS is about 1 and its estimate far too low: the reason implicit sampling is used.
  const implicit::Vec<2> x0(0.0, 0.05);
  const auto imp = ic::estimate_log_psi_implicit(problem, x0, 0, 50, {.seed = 1}, {}, {}, map);
  const auto mc = ic::estimate_log_psi_monte_carlo(problem, x0, 0, 5000, {.seed = 1});
  std::printf("log psi(x0): implicit (%s map) %.4f +- %.4f (ESS %.1f of 50, minimiser %s)\n",
              ic::to_string(map).data(), imp.log_psi, imp.relative_se, imp.ess,
              implicit::to_string(imp.status).data());
  std::printf("             plain MC %.4f +- %.4f (ESS %.1f of 5000)\n", mc.log_psi, mc.relative_se,
              mc.ess);

  // One closed-loop run: the noise realisation is an input, drawn here from a keyed stream.
  Eigen::MatrixXd noise(2, problem.num_steps());
  implicit::Rng rng({.seed = 7, .purpose = implicit::purpose::kProcessNoise});
  rng.fill_normal(noise);
  const auto run = ic::simulate_closed_loop(problem, x0, noise, {.samples = 50, .map = map}, 7);
  double closest = 1e9;
  for (const auto& x : run.x) closest = std::min(closest, (x - implicit::Vec<2>(1.0, 0.0)).norm());
  std::printf(
      "closed loop: final state (%.3f, %.3f), goal (2, 0); closest approach to the "
      "obstacle centre %.3f\n",
      run.x.back()(0), run.x.back()(1), closest);

  // A gate at t = 1: x(1)_y must lie in (-0.8, -0.4) or (0.4, 0.8) (direction a = (0, 1)). The
  // estimator enumerates the two openings, minimises F under each (the path value at the gate
  // clamped to the nearest edge if the free minimiser misses it), and samples a mixture of the
  // two Laplace approximations; samples that hit the gate get weight 0. With --map random each
  // sample runs the random map inside the openings of the mode it picked.
  const ic::HardWall<2> gate{
      .time = 0.5, .direction = implicit::Vec<2>(0.0, 1.0), .openings = {{-0.6, -0.3}, {0.3, 0.6}}};
  const ic::ControlProblem gated(WindyRobot{}, spec, {gate});
  const auto g = ic::estimate_log_psi_implicit(gated, x0, 0, 200, {.seed = 2}, {}, {}, map);
  std::printf("with the gate: log psi %.4f +- %.4f, ESS %.1f of 200, %d samples hit the gate\n",
              g.log_psi, g.relative_se, g.ess, g.wall_hits);
  for (const auto& m : g.modes)
    std::printf("  opening %d: mixture weight %.3f, F at its minimum %.3f, %d of %d samples hit\n",
                m.openings[0], std::exp(m.log_weight), m.phi, m.wall_hits, m.samples);
  const auto gc = ic::estimate_control(gated, x0, 0, {.samples = 200, .map = map}, {.seed = 2});
  std::printf("  control at x0: (%.3f, %.3f)\n", gc.u(0), gc.u(1));
  return 0;
}
