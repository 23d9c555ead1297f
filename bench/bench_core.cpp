// Benchmarks of the implicit sampling core (figures recorded in docs/performance.md, "Core").
//
//   bench_core --benchmark_filter=LinearMap      # per-sample cost of the linear map
//   bench_core --benchmark_filter=Speedup        # parallel_for, 1 vs 2 threads
//
// Target: a smooth non-Gaussian density in m dimensions, the T3 quartic of the math spec §1.6
// generalised: F(x) = sum_i (u_i^2/2 + u_i^4/4), u = A x, A = I + (0.3/m) 1 1^T, with analytic
// gradient and Hessian (checked against automatic derivatives at start-up). Sizes 3 and 5 use
// fixed-size Eigen types, 50 and 200 Eigen::Dynamic.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <vector>

#include "implicit/implicit.hpp"

namespace implicit {
namespace {

/// F(x) = sum_i (u_i^2/2 + u_i^4/4), u = x + c (sum_k x_k) 1: gradient A (u + u^3) and Hessian
/// A D A with D = diag(1 + 3u^2), written out so one evaluation is O(m) (O(m^2) with Hessian).
template <int N>
class CoupledQuartic {
 public:
  static constexpr int Dim = N;
  using Vector = Vec<N>;
  using Matrix = Mat<N>;
  explicit CoupledQuartic(int m = N) : m_(m), c_(0.3 / m) {}
  int dim() const { return m_; }
  double evaluate(const Vector& x, Vector* grad, Matrix* hess) const {
    const double s = c_ * x.sum();
    double f = 0.0, rsum = 0.0, dsum = 0.0;
    if (grad) grad->resize(m_);
    for (int i = 0; i < m_; ++i) {
      const double u = x(i) + s, u2 = u * u;
      f += 0.5 * u2 + 0.25 * u2 * u2;
      if (grad) {
        const double r = u + u * u2;
        (*grad)(i) = r;
        rsum += r;
      }
      dsum += 1.0 + 3.0 * u2;
    }
    if (grad) grad->array() += c_ * rsum;
    if (hess) {
      hess->resize(m_, m_);
      for (int j = 0; j < m_; ++j) {
        const double uj = x(j) + s, dj = 1.0 + 3.0 * uj * uj;
        for (int i = 0; i < m_; ++i) {
          const double ui = x(i) + s, di = 1.0 + 3.0 * ui * ui;
          (*hess)(i, j) = c_ * (di + dj) + c_ * c_ * dsum;
        }
        (*hess)(j, j) += dj;
      }
    }
    return f;
  }

  /// The same F templated on the scalar, for checking the analytic derivatives.
  struct Model {
    double c;
    template <typename V>
    typename V::Scalar operator()(const V& x) const {
      using S = typename V::Scalar;
      S s(0.0);
      for (Eigen::Index k = 0; k < x.size(); ++k) s += c * x(k);
      S f(0.0);
      for (Eigen::Index i = 0; i < x.size(); ++i) {
        const S u = x(i) + s;
        const S u2 = u * u;
        f += 0.5 * u2 + 0.25 * (u2 * u2);
      }
      return f;
    }
  };
  Model model() const { return {c_}; }

 private:
  int m_;
  double c_;
};

// The Laplace approximation at the minimum x = 0 (F = 0, H = A A).
template <int N>
Laplace<N> laplace_of(const CoupledQuartic<N>& f) {
  const int m = f.dim();
  Vec<N> g = Vec<N>::Zero(m);
  Mat<N> h = Mat<N>::Zero(m, m);
  const Vec<N> mu = Vec<N>::Zero(m);
  const double phi = f.evaluate(mu, &g, &h);
  return Laplace<N>::make(mu, phi, h);
}

// A batch of reference variables drawn outside the timed loop.
template <int N>
std::vector<Vec<N>, Eigen::aligned_allocator<Vec<N>>> reference_batch(int m, int count) {
  std::vector<Vec<N>, Eigen::aligned_allocator<Vec<N>>> xi;
  for (int j = 0; j < count; ++j) {
    Rng rng({.seed = 1,
             .step = 0,
             .index = static_cast<std::uint64_t>(j),
             .purpose = purpose::kReference});
    xi.push_back(rng.normal_vector<N>(m));
  }
  return xi;
}

constexpr int kBatch = 1024;

// One linear-map sample given xi: x = mu + L^{-T} xi, then F(x) and log w.
template <int N>
void BM_LinearMapSample(benchmark::State& state) {
  const int m = N == Eigen::Dynamic ? static_cast<int>(state.range(0)) : N;
  const CoupledQuartic<N> f(m);
  const auto lp = laplace_of(f);
  const auto xi = reference_batch<N>(m, kBatch);
  Vec<N> x(m);
  std::size_t j = 0;
  for (auto _ : state) {
    const double lw = linear_map_sample(f, lp, xi[j], x);
    benchmark::DoNotOptimize(lw);
    benchmark::DoNotOptimize(x.data());
    j = (j + 1) % kBatch;
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("m = " + std::to_string(m));
}

// One random-map sample given xi: bracket + safeguarded Newton on the scalar equation.
template <int N>
void BM_RandomMapSample(benchmark::State& state) {
  const int m = N == Eigen::Dynamic ? static_cast<int>(state.range(0)) : N;
  const CoupledQuartic<N> f(m);
  const auto lp = laplace_of(f);
  const auto xi = reference_batch<N>(m, kBatch);
  Vec<N> x(m);
  double lw = 0.0;
  std::size_t j = 0;
  for (auto _ : state) {
    const auto status = random_map_sample(f, lp, xi[j], x, lw);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(lw);
    j = (j + 1) % kBatch;
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("m = " + std::to_string(m));
}

// Drawing the reference variable xi ~ N(0, I_m) from its own stream (Philox + Box-Muller).
template <int N>
void BM_ReferenceVariable(benchmark::State& state) {
  const int m = N == Eigen::Dynamic ? static_cast<int>(state.range(0)) : N;
  std::uint64_t j = 0;
  for (auto _ : state) {
    Rng rng({.seed = 1, .step = 0, .index = j++, .purpose = purpose::kReference});
    const Vec<N> xi = rng.normal_vector<N>(m);
    benchmark::DoNotOptimize(xi.data());
  }
  state.SetItemsProcessed(state.iterations());
}

// The whole per-sample pipeline of sample_with (stream, xi, map, weight, normalisation), serial.
template <int N>
void BM_SampleWithSerial(benchmark::State& state) {
  const int m = N == Eigen::Dynamic ? static_cast<int>(state.range(0)) : N;
  const auto map = state.range(1) == 0 ? MapKind::kLinear : MapKind::kRandom;
  const CoupledQuartic<N> f(m);
  const auto lp = laplace_of(f);
  SamplerOptions o;
  o.map = map;
  o.parallel = false;
  const std::size_t samples = 4096;
  for (auto _ : state) {
    const auto set = sample_with(f, lp, samples, {.seed = 2}, o);
    benchmark::DoNotOptimize(set.log_Z);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(samples));
  state.SetLabel(std::string(map == MapKind::kLinear ? "linear" : "random") +
                 " m = " + std::to_string(m));
}

// One 3-D Newton solve of the quartic from a start at distance ~0.6 from the minimum (as when a
// particle's minimisation starts at its predicted state).
void BM_NewtonSolve3(benchmark::State& state) {
  const CoupledQuartic<3> f;
  const Vec<3> x0(0.4, -0.3, 0.35);
  int iterations = 0;
  for (auto _ : state) {
    const auto r = minimize(f, x0);
    benchmark::DoNotOptimize(r.x.data());
    iterations = r.iterations;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["newton_iterations"] = iterations;
}

// The same solve with automatic (Jet2) derivatives, for comparison.
void BM_NewtonSolve3Autodiff(benchmark::State& state) {
  const auto f = make_autodiff_target<3>(CoupledQuartic<3>().model());
  const Vec<3> x0(0.4, -0.3, 0.35);
  for (auto _ : state) {
    const auto r = minimize(f, x0);
    benchmark::DoNotOptimize(r.x.data());
  }
  state.SetItemsProcessed(state.iterations());
}

// Systematic resampling of n particles (uniform drawn once outside the loop), into a reused
// output vector (as a filter does every step).
void BM_SystematicResampling(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Rng rng({.seed = 3, .step = 0, .index = 0, .purpose = purpose::kUser});
  std::vector<double> lw(n), w(n);
  for (double& l : lw) l = 2.0 * rng.normal();  // log-normal weights: ESS/n ~ 0.02
  normalize_log_weights(lw, w);
  // A different uniform each call, so that the branch predictor cannot learn one fixed pattern
  // (a filter resamples fresh weights every step).
  std::vector<double> uniforms(16);
  for (double& x : uniforms) x = rng.uniform();
  std::vector<std::size_t> ancestors;
  std::size_t call = 0;
  for (auto _ : state) {
    const std::span<const double> u(&uniforms[call++ % uniforms.size()], 1);
    resample(ResamplingScheme::kSystematic, w, u, n, ancestors);
    benchmark::DoNotOptimize(ancestors.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}

// The same through the overload that returns a fresh vector (one allocation of n indices).
void BM_SystematicResamplingAllocating(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Rng rng({.seed = 3, .step = 0, .index = 0, .purpose = purpose::kUser});
  std::vector<double> lw(n), w(n);
  for (double& l : lw) l = 2.0 * rng.normal();
  normalize_log_weights(lw, w);
  std::vector<double> uniforms(16);
  for (double& x : uniforms) x = rng.uniform();
  std::size_t call = 0;
  for (auto _ : state) {
    const std::span<const double> u(&uniforms[call++ % uniforms.size()], 1);
    const auto a = resample(ResamplingScheme::kSystematic, w, u, n);
    benchmark::DoNotOptimize(a.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}

// parallel_for over particles with about 1-2 us of work each (a 50-D random-map sample),
// with 1 and 2 threads; compare the real times of the /1 and /2 runs.
void BM_ParallelSpeedup(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const CoupledQuartic<Eigen::Dynamic> f(50);
  const auto lp = laplace_of(f);
  SamplerOptions o;
  o.map = MapKind::kRandom;
  const std::size_t samples = 4000;
  ThreadLimit limit(threads);
  for (auto _ : state) {
    const auto set = sample_with(f, lp, samples, {.seed = 4}, o);
    benchmark::DoNotOptimize(set.log_Z);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(samples));
  state.counters["threads"] = threads;
}

// A synthetic per-particle kernel of ~1 us (a dependent chain of sqrt/exp), 1 vs 2 threads:
// isolates the parallel_for overhead from memory effects of the sampler.
void BM_ParallelSpeedupKernel(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::size_t n = 20000;
  std::vector<double> out(n);
  ThreadLimit limit(threads);
  for (auto _ : state) {
    parallel_for(n, [&](std::size_t i) {
      double v = 1.0 + 1e-6 * static_cast<double>(i);
      for (int k = 0; k < 60; ++k) v = std::sqrt(v + std::exp(-v));
      out[i] = v;
    });
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
  state.counters["threads"] = threads;
}

BENCHMARK(BM_LinearMapSample<3>);
BENCHMARK(BM_LinearMapSample<5>);
BENCHMARK(BM_LinearMapSample<Eigen::Dynamic>)->Arg(50)->Arg(200);
BENCHMARK(BM_RandomMapSample<3>);
BENCHMARK(BM_RandomMapSample<5>);
BENCHMARK(BM_RandomMapSample<Eigen::Dynamic>)->Arg(50)->Arg(200);
BENCHMARK(BM_ReferenceVariable<3>);
BENCHMARK(BM_ReferenceVariable<5>);
BENCHMARK(BM_ReferenceVariable<Eigen::Dynamic>)->Arg(50)->Arg(200);
BENCHMARK(BM_SampleWithSerial<3>)->Args({3, 0})->Args({3, 1});
BENCHMARK(BM_SampleWithSerial<Eigen::Dynamic>)->Args({200, 0})->Args({200, 1});
BENCHMARK(BM_NewtonSolve3);
BENCHMARK(BM_NewtonSolve3Autodiff);
BENCHMARK(BM_SystematicResampling)->RangeMultiplier(10)->Range(100, 1000000);
BENCHMARK(BM_SystematicResamplingAllocating)->RangeMultiplier(10)->Range(100, 1000000);
BENCHMARK(BM_ParallelSpeedup)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParallelSpeedupKernel)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// The benchmark target's analytic derivatives must be right, or the timings mean nothing.
bool check_benchmark_target() {
  bool ok = true;
  const CoupledQuartic<3> f3;
  const CoupledQuartic<Eigen::Dynamic> f50(50);
  Rng rng({.seed = 5});
  for (int k = 0; k < 3; ++k) {
    const DerivativeCheck c3 = check_derivatives(f3, f3.model(), rng.normal_vector<3>());
    const DerivativeCheck c50 =
        check_derivatives(f50, f50.model(), rng.normal_vector<Eigen::Dynamic>(50));
    if (!c3.ok(1e-12) || !c50.ok(1e-12)) {
      std::fprintf(stderr, "benchmark target derivatives wrong: %s / %s\n", c3.describe().c_str(),
                   c50.describe().c_str());
      ok = false;
    }
  }
  return ok;
}

}  // namespace
}  // namespace implicit

int main(int argc, char** argv) {
  if (!implicit::check_benchmark_target()) return 1;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
