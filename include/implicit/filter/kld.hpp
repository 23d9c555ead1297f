#pragma once
// KLD-sampling (D. Fox, "Adapting the sample size in particle filters through KLD-sampling",
// IJRR 22(12), 2003): resample until the number of particles is large enough that, with
// probability 1 - delta, the K-L divergence between the particle approximation and the true
// posterior (discretised on a grid of bins) stays below epsilon. The number needed grows with the
// number k of bins the drawn particles occupy, so a concentrated cloud gets few particles and a
// spread one (global localisation, ambiguity) gets many.
//
//   KldOptions o{.enabled = true};
//   Rng rng({.seed = seed, .step = n, .index = 0, .purpose = purpose::kResampling});
//   std::vector<std::size_t> ancestors = kld_resample(weights, particles, o, rng);
//   // the next cloud is particles[ancestors[i]], i < ancestors.size()
//
// The option names and meanings follow ROS AMCL (kld_err, kld_z, min/max_particles), so a tuned
// AMCL configuration carries over. The bound and the stopping rule: spec §3.11.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <unordered_set>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::filter {

using robot::Pose;

/// KLD-sampling parameters, named as in ROS AMCL where they mean the same.
struct KldOptions {
  bool enabled = false;
  double kld_err = 0.01;  ///< epsilon: bound on the K-L divergence
  double kld_z = 0.99;    ///< upper standard normal quantile z_{1-delta} (AMCL's meaning)
  std::size_t min_particles = 100;
  std::size_t max_particles = 5000;
  double bin_xy = 0.5;             ///< [m] bin size in x and y
  double bin_heading = 0.1745329;  ///< [rad] (10 degrees)
};

/// Throws InvalidArgument naming the field for bad values (kld_err <= 0, non-finite z,
/// min_particles == 0, min > max, bin sizes <= 0 or non-finite).
inline void validate(const KldOptions& o) {
  require(std::isfinite(o.kld_err) && o.kld_err > 0.0,
          "KldOptions.kld_err: expected a finite value > 0, got {}", o.kld_err);
  require(std::isfinite(o.kld_z), "KldOptions.kld_z: expected a finite value, got {}", o.kld_z);
  require(o.min_particles > 0, "KldOptions.min_particles: expected > 0, got 0");
  require(o.min_particles <= o.max_particles,
          "KldOptions.min_particles: expected <= max_particles ({}), got {}", o.max_particles,
          o.min_particles);
  require(std::isfinite(o.bin_xy) && o.bin_xy > 0.0,
          "KldOptions.bin_xy: expected a finite value > 0, got {}", o.bin_xy);
  require(std::isfinite(o.bin_heading) && o.bin_heading > 0.0,
          "KldOptions.bin_heading: expected a finite value > 0, got {}", o.bin_heading);
}

/// Fox 2003, eq. (the Wilson-Hilferty approximation of the chi-square quantile):
///   n(k) = (k-1)/(2 eps) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3   for k >= 2;  1 for k <= 1.
/// Returned as a double (not rounded) so tests can compare against the closed form.
inline double kld_bound(std::size_t occupied_bins, double kld_err, double kld_z) {
  require(std::isfinite(kld_err) && kld_err > 0.0,
          "kld_bound: expected kld_err finite and > 0, got {}", kld_err);
  require(std::isfinite(kld_z), "kld_bound: expected kld_z finite, got {}", kld_z);
  // One occupied bin: the discrete distribution is a point mass, any single sample is exact.
  if (occupied_bins <= 1) return 1.0;
  const double dof = static_cast<double>(occupied_bins - 1);
  const double a = 2.0 / (9.0 * dof);
  const double b = 1.0 - a + std::sqrt(a) * kld_z;
  return dof / (2.0 * kld_err) * b * b * b;
}

/// The count KLD-sampling stops at for k occupied bins: clamp(ceil(n(k)), min, max).
inline std::size_t kld_particle_count(std::size_t occupied_bins, const KldOptions& o) {
  const double n = std::ceil(kld_bound(occupied_bins, o.kld_err, o.kld_z));
  // Compared as doubles before any conversion: a negative bound (possible for a negative z) or
  // one beyond the range of size_t must not be converted.
  if (!(n > static_cast<double>(o.min_particles))) return o.min_particles;
  if (n >= static_cast<double>(o.max_particles)) return o.max_particles;
  return static_cast<std::size_t>(n);
}

namespace detail {

// Integer bin index floor(v / size), saturated so that a far-away (finite) pose cannot overflow
// the conversion. Saturation merges bins only beyond 2^62 bin widths from the origin.
inline std::int64_t kld_bin_index(double v, double size) {
  constexpr double kLimit = 4.611686018427387904e18;  // 2^62
  const double q = std::floor(v / size);
  return static_cast<std::int64_t>(std::clamp(q, -kLimit, kLimit));
}

// SplitMix64 finaliser: a bijection of 64-bit words with good avalanche, used to combine the
// three bin indices into one well-spread key.
inline std::uint64_t kld_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The 64-bit key of the (x, y, heading) bin of a pose, heading wrapped to [-pi, pi) first so that
// headings 2 pi apart share a bin. Two distinct bins share a key only by a 64-bit hash collision:
// among k <= 10^6 occupied bins that has probability below k^2 / 2^65 < 3e-8, and it would only
// make one step stop slightly earlier.
inline std::uint64_t kld_bin_key(const Pose& p, const KldOptions& o) {
  double h = wrap_angle(p(2));
  if (h >= kPi) h -= 2.0 * kPi;  // rounding in wrap_angle can land exactly on +pi
  const auto ix = static_cast<std::uint64_t>(kld_bin_index(p(0), o.bin_xy));
  const auto iy = static_cast<std::uint64_t>(kld_bin_index(p(1), o.bin_xy));
  const auto ih = static_cast<std::uint64_t>(kld_bin_index(h, o.bin_heading));
  return kld_mix(kld_mix(kld_mix(ix) ^ iy) ^ ih);
}

}  // namespace detail

/// Resampling with a KLD-adapted count (Fox 2003, as AMCL's resampler): draw ancestors i.i.d.
/// from the normalised `weights` (multinomial: an ordered scheme such as systematic would bias an
/// early stop towards low indices), put each drawn particle's pose into its (x, y, heading) bin
/// (heading wrapped to [-pi, pi) before binning), and stop as soon as the number drawn reaches
/// kld_particle_count(bins occupied so far) (and at least min_particles, at most max_particles).
/// Returns the ancestor indices, in draw order. Randomness only from `rng`, serially, so the
/// result is bit-identical for any thread count.
///
/// `weights` need not be normalised, but must be finite, non-negative, with a positive finite
/// sum, and as many as `particles` (at least one); every particle of positive weight must have a
/// finite pose. Otherwise throws InvalidArgument naming the problem.
inline std::vector<std::size_t> kld_resample(std::span<const double> weights,
                                             std::span<const Pose> particles, const KldOptions& o,
                                             Rng& rng) {
  validate(o);
  require(!weights.empty(), "kld_resample: expected at least one weight, got none");
  require(weights.size() == particles.size(),
          "kld_resample: expected as many weights as particles ({}), got {}", particles.size(),
          weights.size());

  // Cumulative sums, once: each draw is then one binary search, O(log M).
  std::vector<double> cumulative(weights.size());
  double total = 0.0;
  std::size_t last_positive = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    const double w = weights[i];
    require(std::isfinite(w) && w >= 0.0,
            "kld_resample: weights[{}]: expected a finite value >= 0, got {}", i, w);
    if (w > 0.0) {
      const Pose& p = particles[i];
      require(p.allFinite(),
              "kld_resample: particles[{}] (weight {}): expected a finite pose, got ({}, {}, {})",
              i, w, p(0), p(1), p(2));
      last_positive = i;
    }
    total += w;
    cumulative[i] = total;
  }
  require(total > 0.0 && std::isfinite(total),
          "kld_resample: expected weights with a positive finite sum, got {}", total);

  // At most min(M, max) bins can be occupied (one per distinct ancestor, one per draw). The count
  // grows with k for 0 <= z < 5.6 (d/dk of n(k)^(1/3) > 0 there), so no draw can go past the
  // count at that many bins: both reservations then hold to the end and the loop allocates
  // nothing (for other z the vector may grow).
  const std::size_t max_bins = std::min(weights.size(), o.max_particles);
  std::vector<std::size_t> ancestors;
  ancestors.reserve(kld_particle_count(max_bins, o));
  // A hash set rather than a sorted vector: every draw looks up (and may insert) a bin, and with
  // up to max_particles occupied bins a sorted vector's insertion shifts O(k) entries per draw,
  // O(k^2) per step, while the hash set is O(1) on average. Reserved for the largest possible
  // number of bins, so it never rehashes.
  std::unordered_set<std::uint64_t> bins;
  bins.reserve(max_bins);

  for (;;) {
    const double target = rng.uniform() * total;
    // First index whose cumulative sum exceeds the target: never a zero-weight particle. Rounding
    // can put the target at or beyond the last sum; that draw goes to the last positive weight.
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
    const std::size_t i =
        std::min(static_cast<std::size_t>(it - cumulative.begin()), last_positive);
    ancestors.push_back(i);
    bins.insert(detail::kld_bin_key(particles[i], o));
    if (ancestors.size() >= kld_particle_count(bins.size(), o)) break;
  }
  return ancestors;
}

}  // namespace implicit::filter
