#pragma once
// Resampling: multinomial, systematic, stratified and residual, with one signature.
//
// Every scheme takes the normalised weights and the uniforms it consumes as input, so its
// decisions can be tested exactly (as in Chopin's `particles`). uniforms_needed(scheme, n) tells
// how many uniforms in (0,1) to pass; draw them from a dedicated stream, e.g.
//
//   Rng rng({seed, step, 0, purpose::kResampling});
//   std::vector<double> u(uniforms_needed(ResamplingScheme::kSystematic, M));
//   for (double& x : u) x = rng.uniform();
//   auto idx = resample(ResamplingScheme::kSystematic, weights, u, M);
//
// Output: ancestor indices in ascending order. Systematic resampling gives every particle
// floor(n w_i) or ceil(n w_i) copies, and has the lowest variance of the four in practice.

#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "implicit/core/rng.hpp"

namespace implicit {

enum class ResamplingScheme { kMultinomial, kSystematic, kStratified, kResidual };

std::string_view to_string(ResamplingScheme s);
/// Parses "multinomial", "systematic", "stratified" or "residual"; throws InvalidArgument
/// otherwise.
ResamplingScheme parse_resampling_scheme(std::string_view name);

/// Number of uniforms resample() consumes for n output particles.
std::size_t uniforms_needed(ResamplingScheme scheme, std::size_t n);

/// Draws n ancestor indices from normalised weights `w` using the given uniforms (each in (0,1)).
/// Throws InvalidArgument for empty or negative or non-finite weights, weights not summing to
/// 1 within 1e-8, or too few uniforms.
std::vector<std::size_t> resample(ResamplingScheme scheme, std::span<const double> w,
                                  std::span<const double> uniforms, std::size_t n);

/// As above, writing the ancestors into `out` (cleared first). Its capacity is reused, so a
/// filter that resamples every step allocates nothing after the first step.
void resample(ResamplingScheme scheme, std::span<const double> w, std::span<const double> uniforms,
              std::size_t n, std::vector<std::size_t>& out);

/// As above, drawing the uniforms from `rng`.
std::vector<std::size_t> resample(ResamplingScheme scheme, std::span<const double> w, std::size_t n,
                                  Rng& rng);

/// True when ess < threshold * m. threshold must be in [0, 1] (1/2 is the usual choice).
bool needs_resampling(double ess, std::size_t m, double threshold);

}  // namespace implicit
