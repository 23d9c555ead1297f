// Data-assimilation costs per member on the variant bocquet2010-k4-q0.5 (docs/cli.md, "implicit
// da"): Lorenz-96, n = 10, F = 8, RK4 dt = 0.05, noise N(0, 0.5^2 I) after every interval, every
// other variable observed with R = 1.5^2 I after every K = 4th interval.
//  * PathMove/<stop>: the implicit filter's move of one member (da/path_objective.hpp): Newton
//    over the 40 noises of its path, then one linear-map sample and its weight. <stop> is
//    "decrement" (path_newton_options(), what the filter uses) or "gradient" (Newton's defaults);
//    the counter iterations is Newton's accepted steps per member.
//  * BootstrapForecast: the bootstrap filter's move of one member: 4 noisy intervals and the
//    log-likelihood of the observation.
// Members: 64 (parent, observation) pairs along a truth run, each parent the truth plus
// N(0, 1) per variable (a forecast ensemble's spread), the observation drawn from the truth four
// intervals later. One iteration covers all 64: read per_member, the CPU time per member.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/path_objective.hpp"

namespace {

using implicit::Rng;
using namespace implicit::da;

constexpr int kDim = 10, kSteps = 4, kMembers = 64;

struct Case {
  Problem problem;
  std::vector<Eigen::VectorXd> parents, observations;
};

const Case& variant() {
  static const Case c = [] {
    Case v;
    v.problem.model = std::make_shared<Lorenz96Model>(Lorenz96(kDim, 8.0), 0.05, 1);
    v.problem.H = Eigen::MatrixXd::Zero(kDim / 2, kDim);
    for (int i = 0; i < kDim / 2; ++i) v.problem.H(i, 2 * i) = 1.0;
    v.problem.R = 1.5 * 1.5 * Eigen::MatrixXd::Identity(kDim / 2, kDim / 2);
    v.problem.Q = 0.5 * 0.5 * Eigen::MatrixXd::Identity(kDim, kDim);
    v.problem.steps_per_observation = kSteps;
    Rng rng({1, 0, 0, implicit::purpose::kData});
    Eigen::VectorXd truth(kDim), z(kDim), e(kDim / 2);
    for (int i = 0; i < kDim; ++i) truth(i) = 8.0 + rng.normal();
    ForecastWorkspace w;
    v.problem.model->prepare(w);
    for (int i = 0; i < 400; ++i) v.problem.model->forecast(truth, w);  // onto the attractor
    for (int m = 0; m < kMembers; ++m) {
      rng.fill_normal(z);
      v.parents.push_back(truth + z);
      for (int k = 0; k < kSteps; ++k) {
        v.problem.model->forecast(truth, w);
        rng.fill_normal(z);
        truth += 0.5 * z;
      }
      rng.fill_normal(e);
      v.observations.push_back(v.problem.H * truth + 1.5 * e);
    }
    return v;
  }();
  return c;
}

void PathMove(benchmark::State& state, bool decrement_stop) {
  const Case& c = variant();
  const implicit::NewtonOptions options =
      decrement_stop ? path_newton_options() : implicit::NewtonOptions{};
  std::vector<PathTerms> terms;
  for (const auto& y : c.observations) terms.emplace_back(c.problem, c.problem.Q, y);
  PathObjective::Scratch s;
  prepare_scratch(c.problem, s);
  Eigen::VectorXd xi(kDim * kSteps), w(kDim * kSteps), x(kDim);
  long iterations = 0, members = 0;
  double sink = 0.0;
  for (auto _ : state) {
    for (int m = 0; m < kMembers; ++m) {
      const PathObjective f(c.problem, terms[m], c.parents[m], s);
      const auto r = implicit::newton_minimize<implicit::DenseFactor<Eigen::Dynamic>>(
          f, Eigen::VectorXd::Zero(kDim * kSteps), options);
      Rng rng({2, 1, static_cast<std::uint64_t>(m), implicit::purpose::kReference});
      rng.fill_normal(xi);
      sink += implicit::linear_map(f, r.x, r.factor, xi, w);
      f.end_state(w, x);
      sink += x(0);
      iterations += r.iterations;
      ++members;
    }
  }
  benchmark::DoNotOptimize(sink);
  state.counters["iterations"] = static_cast<double>(iterations) / members;
  state.counters["per_member"] = benchmark::Counter(
      static_cast<double>(members), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BootstrapForecast(benchmark::State& state) {
  const Case& c = variant();
  const Eigen::MatrixXd lq = c.problem.Q.llt().matrixL(), lr = c.problem.R.llt().matrixL();
  ForecastWorkspace work;
  c.problem.model->prepare(work);
  Eigen::VectorXd x(kDim), z(kDim), r(kDim / 2);
  long members = 0;
  double sink = 0.0;
  for (auto _ : state) {
    for (int m = 0; m < kMembers; ++m) {
      Rng rng({2, 1, static_cast<std::uint64_t>(m), implicit::purpose::kProcessNoise});
      x = c.parents[m];
      for (int k = 0; k < kSteps; ++k) {
        c.problem.model->forecast(x, work);
        rng.fill_normal(z);
        x.noalias() += lq * z;
      }
      r = c.observations[m] - c.problem.H * x;
      lr.triangularView<Eigen::Lower>().solveInPlace(r);
      sink += r.squaredNorm();
      ++members;
    }
  }
  benchmark::DoNotOptimize(sink);
  state.counters["per_member"] = benchmark::Counter(
      static_cast<double>(members), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK_CAPTURE(PathMove, decrement, true);
BENCHMARK_CAPTURE(PathMove, gradient, false);
BENCHMARK(BootstrapForecast);

}  // namespace

BENCHMARK_MAIN();
