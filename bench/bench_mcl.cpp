// Monte Carlo localization costs (paper Table 5's CPU column, spec §3.9 targets):
//  * one laser update of one particle, bootstrap vs implicit, 1 / 3 / 6 landmarks in view
//    (unlabelled detections, association over a 15-landmark map included);
//  * one prediction-only step of one particle;
//  * a whole Car Park run (5000 steps, 505 scans) at M = 100 and M = 10 000, 1 and 2 threads.
// Per-particle benchmarks: one iteration = one particle (read the CPU column; the counter
// `evaluations` is the Newton objective evaluations per particle). Whole runs: the
// counter ms_per_step (wall time of the filter loop / 5000 steps).
#include <benchmark/benchmark.h>

#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/LU>

#include "implicit/core/parallel.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/carpark.hpp"

namespace {

using namespace implicit;
using filter::LabelledMeasurement;
using robot::Landmark;
using robot::Measurement;
using robot::Pose;

// The filter's step as a proposal sees it: the landmark model, the detections and the context.
// Not copyable: the context points into it.
struct UpdateFixture {
  using Observation = robot::LandmarkObservation<robot::RangeBearingSensor>;
  robot::UteModel model;
  robot::RangeBearingSensor sensor;
  std::vector<Landmark> map;
  std::vector<LabelledMeasurement> z;
  std::vector<Pose> previous;
  std::optional<Observation> observation;
  Observation::Prepared detections;
  filter::ObservationContext<robot::UteModel, Observation> ctx;

  explicit UpdateFixture(int in_view) {
    const Pose truth(0.0, 0.0, kPi / 2);  // heading north: bearing pi/2 is straight ahead
    for (int k = 0; k < 15; ++k) {
      if (k < in_view) {
        const double a = kPi / 2 + 0.8 * (k - 0.5 * (in_view - 1)) / std::max(1, in_view);
        map.emplace_back(8.0 * std::cos(a) + 0.3 * k, 8.0 * std::sin(a) + 0.5 * k);
      } else {
        map.emplace_back(-40.0 + 6.0 * k, -30.0);  // behind: never gated
      }
    }
    for (int k = 0; k < in_view; ++k) {
      Measurement h = sensor.predict(truth, map[static_cast<std::size_t>(k)]);
      h += Vec<2>(0.1 * std::sin(k + 1.0), 0.01 * std::cos(k + 1.0));
      z.push_back({h, -1});
    }
    const Pose before = truth - model.dt() * model.rate(truth, robot::Control(3.0, 0.05));
    for (int j = 0; j < 1024; ++j)
      previous.push_back(
          before + Vec<3>(0.1 * std::sin(j), 0.1 * std::cos(1.3 * j), 0.01 * std::sin(0.7 * j)));
    robot::LandmarkMap landmarks;
    for (std::size_t i = 0; i < map.size(); ++i) landmarks.add(static_cast<int>(i), map[i]);
    observation.emplace(sensor, std::move(landmarks));
    detections = observation->view(z);
    ctx.motion = &model;
    ctx.observation = &*observation;
    ctx.u = robot::Control(3.0, 0.05);
    ctx.z = &detections;
  }
  UpdateFixture(const UpdateFixture&) = delete;
  UpdateFixture& operator=(const UpdateFixture&) = delete;
};

template <typename Proposal>
void BM_LaserUpdatePerParticle(benchmark::State& state) {
  UpdateFixture f(static_cast<int>(state.range(0)));
  const Proposal proposal{};
  std::uint64_t j = 0;
  double sink = 0.0;
  double evaluations = 0.0;
  for (auto _ : state) {
    Rng rng({1, 1, j, Proposal::kPurpose});
    filter::ParticleStats st;
    Pose next;
    sink += proposal.propose(f.ctx, f.previous[j & 1023], rng, next, st);
    evaluations += st.iterations;
    benchmark::DoNotOptimize(next);
    ++j;
  }
  benchmark::DoNotOptimize(sink);
  // Newton objective evaluations with derivatives per particle (0 for the bootstrap).
  state.counters["evaluations"] = evaluations / static_cast<double>(state.iterations());
}
BENCHMARK(BM_LaserUpdatePerParticle<filter::BootstrapProposal>)->Arg(1)->Arg(3)->Arg(6);
BENCHMARK(BM_LaserUpdatePerParticle<filter::ImplicitProposal>)->Arg(1)->Arg(3)->Arg(6);

template <typename Proposal>
void BM_PredictionPerParticle(benchmark::State& state) {
  UpdateFixture f(0);
  f.ctx.z = nullptr;
  const Proposal proposal{};
  std::uint64_t j = 0;
  for (auto _ : state) {
    Rng rng({1, 1, j, Proposal::kPurpose});
    filter::ParticleStats st;
    Pose next;
    benchmark::DoNotOptimize(proposal.propose(f.ctx, f.previous[j & 1023], rng, next, st));
    benchmark::DoNotOptimize(next);
    ++j;
  }
}
BENCHMARK(BM_PredictionPerParticle<filter::BootstrapProposal>);
BENCHMARK(BM_PredictionPerParticle<filter::ImplicitProposal>);

const filter::LocalizationProblem& carpark() {
  static const filter::LocalizationProblem p = [] {
    const robot::UteModel model;
    return filter::make_problem(
        robot::carpark_to_log(robot::load_carpark(robot::default_carpark_dir()), model),
        model.dt());
  }();
  return p;
}

// Whole Car Park run, config A; args: particles, threads.
template <typename Proposal>
void BM_CarParkRun(benchmark::State& state) {
  const auto& problem = carpark();
  const robot::UteModel model;
  const robot::RangeBearingSensor sensor;
  filter::FilterOptions options;
  options.particles = static_cast<std::size_t>(state.range(0));
  ThreadLimit limit(static_cast<int>(state.range(1)));
  double wall = 0.0;
  for (auto _ : state) {
    const auto run = filter::run_localization(problem, model, sensor, Proposal{}, options);
    wall += run.seconds;
    benchmark::DoNotOptimize(run.steps.back().mean);
  }
  state.counters["ms_per_step"] = 1e3 * wall /
                                  (static_cast<double>(state.iterations()) *
                                   static_cast<double>(problem.schedule.steps.size()));
}
// M = 100 and 10 000 particles, 1 and 2 threads: per-step cost and parallel speedup.
void car_park_args(benchmark::internal::Benchmark* b) {
  b->ArgsProduct({{100, 10000}, {1, 2}})
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1)
      ->UseRealTime();
}
BENCHMARK(BM_CarParkRun<filter::ImplicitProposal>)->Apply(car_park_args);
BENCHMARK(BM_CarParkRun<filter::BootstrapProposal>)->Apply(car_park_args);

}  // namespace

BENCHMARK_MAIN();
