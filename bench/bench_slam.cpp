// SLAM benchmarks: cost per filter step for every method (M = 100, synthetic Car Park data),
// per-step cost against the number of landmarks in the map (up to 10 000), resampling cost and
// memory of copy-on-write maps against plain per-particle vectors.
//
//   bench_slam --benchmark_filter='Step'          # per step, per method
//   bench_slam --benchmark_filter='Resampling'    # persistent vs naive copies
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/ekf_slam.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/landmark_index.hpp"
#include "implicit/slam/landmark_map.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {
namespace {

const SlamScenario& scenario() {
  static const SlamScenario s = load_carpark_scenario(default_data_dir());
  return s;
}

const SlamDataset& carpark_data() {
  static const SlamDataset d = generate_synthetic(scenario(), SyntheticConfig(), 1);
  return d;
}

SlamMethod method_of(int i) {
  return std::array{SlamMethod::kEkf, SlamMethod::kFastSlam1, SlamMethod::kFastSlam2,
                    SlamMethod::kImplicit, SlamMethod::kImplicitRb}[static_cast<std::size_t>(i)];
}

// One filter step (move + one detection + weights + resampling when due), single thread, M
// particles, averaged over the 5000 steps of a synthetic data set (restarted when it ends).
void BM_Step(benchmark::State& state) {
  const ThreadLimit one(1);
  const SlamDataset& d = carpark_data();
  SlamOptions opt;
  opt.method = method_of(static_cast<int>(state.range(0)));
  opt.particles = static_cast<int>(state.range(1));
  auto filter = make_slam_filter(opt, d.initial_pose);
  std::size_t n = 1;
  for (auto _ : state) {
    if (n > d.steps()) {
      state.PauseTiming();
      filter = make_slam_filter(opt, d.initial_pose);
      n = 1;
      state.ResumeTiming();
    }
    filter->step(n, d.control(n), d.observations(n));
    ++n;
  }
  state.SetLabel(std::string(to_string(opt.method)));
  // Seconds per particle-step (printed with an SI prefix, e.g. 1.2u = 1.2 microseconds).
  state.counters["per_particle"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * opt.particles,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Step)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {100}})
    ->ArgNames({"method", "M"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step)
    ->ArgsProduct({{4}, {10, 1000}})
    ->ArgNames({"method", "M"})
    ->Unit(benchmark::kMicrosecond);

// Per-step cost against the map size N: every particle starts with the N landmarks of a dense
// field and runs along the route. With known association (assoc = 0) the per-particle map work
// is O(log N); with maximum-likelihood association each particle also searches its map for the
// detected landmark: through the spatial grid index (assoc = 1) or the linear scan (assoc = 2).
void BM_StepVsLandmarks(benchmark::State& state) {
  const ThreadLimit one(1);
  const int landmarks = static_cast<int>(state.range(1));
  const SlamScenario sc = make_dense_scenario(scenario(), 1, landmarks, 3);
  const SlamDataset d = generate_synthetic(sc, SyntheticConfig(), 2);
  SlamOptions opt;
  opt.method = method_of(static_cast<int>(state.range(0)));
  opt.association = state.range(2) == 0 ? Association::kKnown : Association::kMaximumLikelihood;
  opt.association_index = state.range(2) != 2;  // 2: ML through the linear scan
  opt.particles = 100;
  auto make = [&] {
    auto f = make_slam_filter(opt, d.initial_pose);
    f->set_known_map(d.landmarks);
    return f;
  };
  auto filter = make();
  std::size_t n = 1;
  for (auto _ : state) {
    if (n > d.steps()) {
      state.PauseTiming();
      filter = make();
      n = 1;
      state.ResumeTiming();
    }
    filter->step(n, d.control(n), d.observations(n));
    ++n;
  }
  state.SetLabel(fmt::format("{} {}{}", to_string(opt.method), to_string(opt.association),
                             state.range(2) == 2 ? " scan" : ""));
  state.counters["landmarks"] = landmarks;
  state.counters["map_bytes_per_particle"] =
      static_cast<double>(filter->map_bytes()) / opt.particles;
}
BENCHMARK(BM_StepVsLandmarks)
    ->ArgsProduct({{2, 4}, {15, 100, 1000, 10000}, {0, 1, 2}})
    ->ArgNames({"method", "N", "assoc"})
    ->Unit(benchmark::kMicrosecond);

// One maximum-likelihood association at a FIXED landmark density (one landmark per 25 m^2, the
// field growing with N): the linear scan (mode 0) is O(N), the grid index (mode 1) scores only
// the landmarks near the detection and walks the landmark tree, O(log N).
void BM_AssociationVsLandmarks(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const bool indexed = state.range(1) != 0;
  const double side = std::sqrt(25.0 * static_cast<double>(n));
  Rng rng({5, n, 0, purpose::kData});
  LandmarkEstimates map;
  LandmarkGridIndex index;
  for (std::size_t k = 0; k < n; ++k) {
    // One draw per declarator: the order of function arguments is unspecified.
    const double mx = side * rng.uniform(), my = side * rng.uniform();
    const Vec<2> m(mx, my);
    map.push_back({m, 0.05 * Mat<2>::Identity()});
    index.insert(static_cast<std::uint32_t>(k), m, 0.1);
  }
  const robot::RangeBearingSensor sensor;
  const robot::UteModel model{robot::UteParams{}};
  // Detections of random landmarks from 8 m away, facing them.
  constexpr std::size_t kQueries = 256;
  std::vector<Pose> poses(kQueries);
  std::vector<Measurement> zs(kQueries);
  for (std::size_t q = 0; q < kQueries; ++q) {
    const Vec<2> m =
        map.get(static_cast<std::size_t>(rng.uniform() * static_cast<double>(n)) % n).mean;
    const double a = 2.0 * kPi * rng.uniform();
    poses[q] = Pose(m(0) - 8.0 * std::cos(a), m(1) - 8.0 * std::sin(a), a);
    zs[q] = sensor.predict(poses[q], m) + Vec<2>(0.2, 0.03).cwiseProduct(rng.normal_vector<2>());
  }
  const Mat<3> sigma1 = model.process_covariance(poses[0], Control(3.0, 0.05));
  std::vector<std::uint32_t> scratch;
  std::size_t q = 0, matched = 0;
  for (auto _ : state) {
    const auto a = indexed ? associate_indexed(map, index, sensor, poses[q], sigma1, zs[q],
                                               robot::kChiSquare2Dof99, scratch)
                           : associate_scan(map, sensor, poses[q], sigma1, zs[q],
                                            robot::kChiSquare2Dof99, 0.1);
    matched += a.matched() ? 1 : 0;
    benchmark::DoNotOptimize(a);
    q = (q + 1) % kQueries;
  }
  state.SetLabel(indexed ? "grid index" : "linear scan");
  state.counters["matched"] = static_cast<double>(matched) /
                              static_cast<double>(std::max<std::size_t>(1, state.iterations()));
}
BENCHMARK(BM_AssociationVsLandmarks)
    ->ArgsProduct({{100, 1000, 10000, 100000}, {0, 1}})
    ->ArgNames({"N", "indexed"});

// EKF-SLAM's Kalman update against the map size: O(n^2) in the state dimension n = 3 + 2N,
// the reason EKF-SLAM does not scale to large maps (Victoria Park) and the particle filters do.
void BM_EkfUpdateVsLandmarks(benchmark::State& state) {
  const int landmarks = static_cast<int>(state.range(0));
  EkfSlamCore ekf(Vec<3>(0.0, 0.0, 0.3), 0.01 * Mat<3>::Identity());
  const Mat23 jx = (Mat23() << -0.6, -0.8, 0.0, 0.05, -0.04, -1.0).finished();
  const Mat<2> jm = (Mat<2>() << 0.6, 0.8, -0.05, 0.04).finished();
  const Mat<2> r = Vec<2>(0.01, 1e-4).asDiagonal();
  for (int k = 0; k < landmarks; ++k)
    ekf.augment(Vec<2>(k % 100, k / 100), jx, jm * r * jm.transpose());
  int k = 0;
  for (auto _ : state) {
    ekf.update(k, Vec<2>(1e-3, -1e-4), jx, jm, r);
    k = (k + 7) % landmarks;
  }
  state.counters["state_dim"] = 3 + 2 * landmarks;
}
BENCHMARK(BM_EkfUpdateVsLandmarks)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);

// Resampling M = 100 particles whose maps hold N landmarks, then one landmark update per
// particle (what the next step does): copy-on-write maps vs plain vectors deep-copied.
std::vector<std::size_t> ancestors(std::size_t m, std::uint64_t step) {
  Rng rng({7, step, 0, purpose::kResampling});
  std::vector<std::size_t> a(m);
  for (auto& x : a) x = static_cast<std::size_t>(rng.uniform() * static_cast<double>(m)) % m;
  std::sort(a.begin(), a.end());
  return a;
}

void BM_ResamplingPersistent(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::size_t m = 100;
  LandmarkEstimates base;
  for (std::size_t k = 0; k < n; ++k)
    base.push_back({Vec<2>(static_cast<double>(k), 0.0), Mat<2>::Identity()});
  std::vector<LandmarkEstimates> maps(m, base), next(m);
  std::uint64_t step = 0;
  for (auto _ : state) {
    const auto a = ancestors(m, ++step);
    for (std::size_t j = 0; j < m; ++j) next[j] = maps[a[j]];
    maps.swap(next);
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t k = (step * 7919 + j) % n;
      LandmarkEstimate l = maps[j].get(k);
      l.mean(1) += 1e-3;
      maps[j].set(k, l);
    }
  }
  std::unordered_set<const void*> seen;
  std::size_t bytes = 0;
  for (const auto& mp : maps) bytes += mp.unique_bytes(seen);
  state.counters["landmarks"] = static_cast<double>(n);
  state.counters["bytes_per_particle"] = static_cast<double>(bytes) / m;
}
BENCHMARK(BM_ResamplingPersistent)
    ->Arg(15)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMicrosecond);

void BM_ResamplingNaiveCopy(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::size_t m = 100;
  std::vector<LandmarkEstimate> base(n);
  for (std::size_t k = 0; k < n; ++k)
    base[k] = {Vec<2>(static_cast<double>(k), 0.0), Mat<2>::Identity()};
  std::vector<std::vector<LandmarkEstimate>> maps(m, base), next(m);
  std::uint64_t step = 0;
  for (auto _ : state) {
    const auto a = ancestors(m, ++step);
    for (std::size_t j = 0; j < m; ++j) next[j] = maps[a[j]];
    maps.swap(next);
    for (std::size_t j = 0; j < m; ++j) maps[j][(step * 7919 + j) % n].mean(1) += 1e-3;
  }
  state.counters["landmarks"] = static_cast<double>(n);
  state.counters["bytes_per_particle"] = static_cast<double>(n * sizeof(LandmarkEstimate));
}
BENCHMARK(BM_ResamplingNaiveCopy)
    ->Arg(15)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace implicit::slam

BENCHMARK_MAIN();
