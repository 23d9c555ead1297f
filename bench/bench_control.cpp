// Timing of path integral control: one control evaluation for the double slit (M = 50), the
// robot arm (n = 200; closed form and generic) and Himmelblau (M = 50), and the whole of Table 2 (4
// x 500 closed-loop runs, parallel over runs, through the experiment's aggregation in
// experiments/slit_table.hpp); the generic estimator with the random map and with a hard wall
// (mixture over the openings). Figures are recorded in docs/performance.md.
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "experiments/slit_table.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/control/himmelblau.hpp"
#include "implicit/control/path_integral.hpp"
#include "implicit/control/robot_arm.hpp"

using namespace implicit::control;

namespace {

void BM_SlitControl(benchmark::State& state, SlitEstimator estimator, SlitSampling sampling) {
  const DoubleSlit slit;
  const int M = static_cast<int>(state.range(0));
  std::uint64_t i = 0;
  for (auto _ : state) {
    const auto e = slit.estimate_control(1.0, 0, M, estimator, {1, i++, 0, 0}, sampling);
    benchmark::DoNotOptimize(e.u);
  }
}
BENCHMARK_CAPTURE(BM_SlitControl, corrected_wall, SlitEstimator::kFrozenWall, SlitSampling::kWall)
    ->Arg(50)
    ->Arg(500);
BENCHMARK_CAPTURE(BM_SlitControl, corrected_path, SlitEstimator::kFrozenWall, SlitSampling::kPath)
    ->Arg(50);
BENCHMARK_CAPTURE(BM_SlitControl, paper_wall, SlitEstimator::kPaper, SlitSampling::kWall)->Arg(50);

void BM_ArmControl(benchmark::State& state) {
  const ArmProblem problem;
  const implicit::Vec<4> x(0.2, -0.1, 0.3, -0.2);
  for (auto _ : state) benchmark::DoNotOptimize(arm_path_integral_control(x, 200, problem));
}
BENCHMARK(BM_ArmControl);

// The same control from the generic estimator: each joint a ControlProblem with partial noise
// (dense Hessian of the 200 velocities, central difference along G).
void BM_ArmControlGeneric(benchmark::State& state) {
  const ArmProblem problem;
  const std::array<ArmJointProblem, 2> joints{arm_joint_problem(problem, 0),
                                              arm_joint_problem(problem, 1)};
  const implicit::Vec<4> x(0.2, -0.1, 0.3, -0.2);
  EstimatorOptions o;
  o.samples = 1;
  for (auto _ : state)
    for (int j = 0; j < 2; ++j)
      benchmark::DoNotOptimize(estimate_control(joints[static_cast<std::size_t>(j)],
                                                implicit::Vec<2>(x(j), x(2 + j)), 0, o,
                                                {1, 0, static_cast<std::uint64_t>(j), 0})
                                   .u);
}
BENCHMARK(BM_ArmControlGeneric);

void BM_HimmelblauControl(benchmark::State& state) {
  const HimmelblauProblem pb;
  const implicit::Vec<2> warm(-3.78, -3.28);
  std::uint64_t i = 0;
  for (auto _ : state) {
    const auto e = himmelblau_control(pb, pb.x0, 0, 50, warm, {1, i++, 0, 0});
    benchmark::DoNotOptimize(e.u);
  }
}
BENCHMARK(BM_HimmelblauControl);

// The same problem through estimate_control directly, started from the drift path instead of
// himmelblau_control's straight line to a good end point (autodiff, banded Newton on the 40-D
// path), with the linear map (arg 0) and the random map (arg 1: one scalar root per sample, O(n)
// jet evaluations per root iteration).
void BM_GenericHimmelblauControl(benchmark::State& state) {
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.noise_covariance = 0.01 * implicit::Mat<2>::Identity();
  s.control_cost = 0.01 * implicit::Mat<2>::Identity();
  s.horizon = 20.0;
  s.dt = 1.0;
  const ControlProblem problem(HimmelblauModel{}, s);
  const SamplingMap map = state.range(0) == 0 ? SamplingMap::kLinear : SamplingMap::kRandom;
  state.SetLabel(state.range(0) == 0 ? "linear map" : "random map");
  std::uint64_t i = 0;
  for (auto _ : state) {
    const auto c = estimate_control(problem, implicit::Vec<2>(-1, -4), 0,
                                    {.samples = 50, .map = map}, {1, i++, 0, 0});
    benchmark::DoNotOptimize(c.u);
  }
}
BENCHMARK(BM_GenericHimmelblauControl)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The double slit through the generic problem with a HardWall: two constrained minima (range-
// space Newton on the 100-D path), a two-component mixture, M samples, frozen-wall FD-CRN.
// Without the wall: the same 100-D path, for the cost of the wall machinery alone. With the path
// resolved at the wall and the horizon only (PathGrid::kWallsAndHorizon, exact here): a 2-D path.
void BM_GenericSlitControl(benchmark::State& state, bool wall, SamplingMap map,
                           PathGrid grid = PathGrid::kEveryStep) {
  ControlSpec<1, 1> s;
  s.path_grid = grid;
  s.G << 1.0;
  s.noise_covariance << 1.0;
  s.control_cost << 0.1;
  s.horizon = 2.0;
  s.dt = 0.02;
  std::vector<HardWall<1>> walls;
  if (wall) walls.push_back({.time = 1.0, .openings = {{-6.0, -4.0}, {6.0, 8.0}}});
  const ControlProblem problem(FreeWalkerModel{}, s, walls);
  const int M = static_cast<int>(state.range(0));
  std::uint64_t i = 0;
  for (auto _ : state) {
    const auto c = estimate_control(problem, implicit::Vec<1>(1.0), 0,
                                    {.samples = M, .map = map, .fd_step = 1e-3}, {1, i++, 0, 0});
    benchmark::DoNotOptimize(c.u);
  }
}
BENCHMARK_CAPTURE(BM_GenericSlitControl, mixture_linear, true, SamplingMap::kLinear)
    ->Arg(50)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GenericSlitControl, mixture_random, true, SamplingMap::kRandom)
    ->Arg(50)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GenericSlitControl, mixture_linear_2d, true, SamplingMap::kLinear,
                  PathGrid::kWallsAndHorizon)
    ->Arg(50)
    ->Arg(500)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GenericSlitControl, mixture_random_2d, true, SamplingMap::kRandom,
                  PathGrid::kWallsAndHorizon)
    ->Arg(50)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GenericSlitControl, no_wall_linear, false, SamplingMap::kLinear)
    ->Arg(50)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GenericSlitControl, no_wall_random, false, SamplingMap::kRandom)
    ->Arg(50)
    ->Unit(benchmark::kMicrosecond);

void BM_SlitTable2(benchmark::State& state, SlitEstimator estimator,
                   implicit::experiments::SlitImplementation implementation) {
  const DoubleSlit slit;
  for (auto _ : state) {
    for (int M : {10, 50, 100, 500}) {
      implicit::experiments::SlitTableOptions o;
      o.samples = M;
      o.runs = 500;
      o.estimator = estimator;
      o.implementation = implementation;
      benchmark::DoNotOptimize(implicit::experiments::run_slit_table(slit, o).error_u_mean);
    }
  }
}
BENCHMARK_CAPTURE(BM_SlitTable2, corrected, SlitEstimator::kFrozenWall,
                  implicit::experiments::SlitImplementation::kGeneric)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(BM_SlitTable2, paper, SlitEstimator::kPaper,
                  implicit::experiments::SlitImplementation::kGeneric)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);
// The same tables with DoubleSlit's wall-space estimator (one scalar per sample).
BENCHMARK_CAPTURE(BM_SlitTable2, corrected_wall_space, SlitEstimator::kFrozenWall,
                  implicit::experiments::SlitImplementation::kWallSpace)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(BM_SlitTable2, paper_wall_space, SlitEstimator::kPaper,
                  implicit::experiments::SlitImplementation::kWallSpace)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
