#pragma once
// Implicit sampling in one call: minimise F, then draw M weighted samples with the linear or
// random map (or a mixture over several minima).
//
//   auto target = implicit::make_autodiff_target<2>(model);
//   auto set = implicit::sample(target, x0, 1000, {.seed = 42});
//   set.log_Z;   // log of the mean weight: an unbiased estimate of Z = ∫ exp(-F) in the weight
//   set.ess;     // effective sample size 1 / sum w_bar^2
//   set.mean();  // self-normalised posterior mean
//
// Sample j draws its reference variable from the stream (seed, step, j, purpose::kReference), so
// the result is bit-identical for any number of threads.

#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <vector>

#include "implicit/core/laplace.hpp"
#include "implicit/core/linear_map.hpp"
#include "implicit/core/minimize.hpp"
#include "implicit/core/mixture.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/random_map.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"

namespace implicit {

struct SamplerOptions {
  MapKind map = MapKind::kLinear;
  MinimizeOptions minimize{};
  RandomMapOptions random_map{};
  bool parallel = true;
};

template <int N>
struct SampleSet {
  Eigen::Matrix<double, N, Eigen::Dynamic> x;  ///< samples, one per column
  std::vector<double> log_weights;             ///< log w_j with every constant (E[w] = Z)
  std::vector<double> weights;                 ///< normalised weights w_bar_j
  double log_Z = -std::numeric_limits<double>::infinity();  ///< log of the mean weight
  double ess = 0.0;                                         ///< effective sample size
  int zero_weight = 0;   ///< samples with weight 0 (outside the support, or map failures)
  int map_failures = 0;  ///< samples not placed: random-map root failures; linear map: F = -inf
                         ///< or NaN at the sample (both get weight zero)
  MinimizeStatus minimize_status = MinimizeStatus::kConverged;
  std::vector<Laplace<N>> modes;  ///< the Laplace approximation(s) used

  Vec<N> mean() const { return weighted_mean<N>(x, weights); }
  Mat<N> covariance() const { return weighted_covariance<N>(x, weights); }
  std::size_t size() const { return log_weights.size(); }
};

namespace detail {
/// Room for M samples of dimension m; a size the machine cannot hold is bad input, not bad_alloc.
template <int N>
void allocate(SampleSet<N>& s, int m, std::size_t M) {
  const double gib = static_cast<double>(M) * (m + 2) * sizeof(double) / (1 << 30);
  try {
    // The vectors first: beyond their max_size they throw length_error before asking malloc
    // (a sanitizer's allocator aborts on absurd sizes instead of throwing bad_alloc).
    s.log_weights.assign(M, 0.0);
    s.weights.reserve(M);
    s.x.resize(m, static_cast<Eigen::Index>(M));
  } catch (const std::exception&) {  // bad_alloc, or length_error beyond a vector's max_size
    throw InvalidArgument(fmt::format(
        "implicit sampling: expected a number of samples that fits in memory, got M = {} "
        "({:.3g} GiB)",
        M, gib));
  }
}

template <int N>
void finish(SampleSet<N>& s) {
  s.weights.resize(s.log_weights.size());
  const auto summary = normalize_log_weights(s.log_weights, s.weights);
  s.log_Z = summary.log_mean;
  // All weights zero: the uniform weights are a placeholder, so no sample is effective.
  s.ess = summary.all_zero ? 0.0 : summary.ess;
  for (double l : s.log_weights)
    if (!std::isfinite(l)) ++s.zero_weight;
}
}  // namespace detail

/// Draws M samples around a given Laplace approximation (no minimisation).
template <Target T>
SampleSet<T::Dim> sample_with(const T& f, const Laplace<T::Dim>& lp, std::size_t M,
                              const StreamKey& key, const SamplerOptions& options = {}) {
  constexpr int N = T::Dim;
  require(M > 0, "implicit sampling: expected at least one sample, got {}", M);
  const int m = f.dim();
  require(lp.dim() == m,
          "implicit sampling: the Laplace approximation has dimension {}, the target {}", lp.dim(),
          m);
  SampleSet<N> s;
  s.modes = {lp};
  detail::allocate(s, m, M);
  std::vector<unsigned char> failed(M, 0);
  auto one = [&](std::size_t j) {
    Rng rng({key.seed, key.step, j, purpose::kReference});
    const Vec<N> xi = rng.normal_vector<N>(m);
    Vec<N> x(m);
    if (options.map == MapKind::kLinear) {
      s.log_weights[j] = linear_map_sample(f, lp, xi, x);
      // F = -inf or NaN at a sample (an unbounded density): weight zero and counted, as the
      // random map does, not a +inf weight that makes the normalisation throw.
      if (std::isnan(s.log_weights[j]) || s.log_weights[j] == kInfinity) {
        s.log_weights[j] = -kInfinity;
        failed[j] = 1;
      }
    } else {
      failed[j] = random_map_sample(f, lp, xi, x, s.log_weights[j], options.random_map) !=
                  RandomMapStatus::kOk;
    }
    s.x.col(static_cast<Eigen::Index>(j)) = x;
  };
  if (options.parallel)
    parallel_for(M, one);
  else
    for (std::size_t j = 0; j < M; ++j) one(j);
  for (auto fl : failed) s.map_failures += fl;
  detail::finish(s);
  return s;
}

/// Minimises F from x0, then draws M samples. Throws InvalidArgument if the minimiser fails or
/// the Hessian at the minimum is not positive definite (see Laplace::make).
template <Target T>
SampleSet<T::Dim> sample(const T& f, const typename T::Vector& x0, std::size_t M,
                         const StreamKey& key, const SamplerOptions& options = {}) {
  require(x0.size() == f.dim(), "implicit sampling: start point has dimension {}, expected {}",
          x0.size(), f.dim());
  const auto r = minimize(f, x0, options.minimize);
  require(r.status == MinimizeStatus::kConverged,
          "implicit sampling: minimising F failed with status '{}' after {} iterations",
          to_string(r.status), r.iterations);
  auto s = sample_with(f, Laplace<T::Dim>::make(r.x, r.value, r.hessian), M, key, options);
  s.minimize_status = r.status;
  return s;
}

/// Draws M samples from a mixture over several minima (linear map per component).
template <Target T>
SampleSet<T::Dim> sample_mixture(const T& f, const MixtureProposal<T::Dim>& q, std::size_t M,
                                 const StreamKey& key, const SamplerOptions& options = {}) {
  constexpr int N = T::Dim;
  require(M > 0, "implicit sampling: expected at least one sample, got {}", M);
  const int m = f.dim();
  SampleSet<N> s;
  s.modes = q.components();
  detail::allocate(s, m, M);
  auto one = [&](std::size_t j) {
    Rng rng({key.seed, key.step, j, purpose::kReference});
    const double u = rng.uniform();
    const Vec<N> xi = rng.normal_vector<N>(m);
    Vec<N> x(m);
    s.log_weights[j] = q.sample(f, u, xi, x);
    s.x.col(static_cast<Eigen::Index>(j)) = x;
  };
  if (options.parallel)
    parallel_for(M, one);
  else
    for (std::size_t j = 0; j < M; ++j) one(j);
  detail::finish(s);
  return s;
}

}  // namespace implicit
