// Resampling: exact properties (systematic counts, residual's deterministic part, sorted output),
// unbiasedness of all four schemes, and the ESS trigger.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "implicit/implicit.hpp"

namespace implicit {
namespace {

constexpr ResamplingScheme kAllSchemes[] = {
    ResamplingScheme::kMultinomial, ResamplingScheme::kSystematic, ResamplingScheme::kStratified,
    ResamplingScheme::kResidual};

// Normalised random weights from exponentials (a flat Dirichlet), with every fifth set to zero.
std::vector<double> random_weights(Rng& rng, std::size_t n) {
  std::vector<double> w(n);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    w[i] = (i % 5 == 4) ? 0.0 : -std::log(rng.uniform());
    sum += w[i];
  }
  if (sum == 0.0) w[0] = sum = 1.0;
  for (double& x : w) x /= sum;
  return w;
}

std::vector<double> uniforms(Rng& rng, ResamplingScheme scheme, std::size_t n) {
  std::vector<double> u(uniforms_needed(scheme, n));
  for (double& x : u) x = rng.uniform();
  return u;
}

std::vector<int> counts(const std::vector<std::size_t>& ancestors, std::size_t n) {
  std::vector<int> c(n, 0);
  for (std::size_t a : ancestors) ++c.at(a);
  return c;
}

TEST(Resampling, SystematicCountsAreFloorOrCeil) {
  // Exact property: particle i receives floor(N w_i) or ceil(N w_i) copies, for any uniform.
  // 2000 random weight vectors of random sizes, N output particles in 1..300. Zero weights get
  // exactly zero copies (also the trailing ones, where a cumulative sum below 1 could misindex).
  Rng rng({.seed = 1, .step = 0, .index = 0, .purpose = purpose::kUser});
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t n = 1 + static_cast<std::size_t>(rng.uniform() * 60);
    const std::size_t big_n = 1 + static_cast<std::size_t>(rng.uniform() * 300);
    const auto w = random_weights(rng, n);
    const auto u = uniforms(rng, ResamplingScheme::kSystematic, big_n);
    const auto a = resample(ResamplingScheme::kSystematic, w, u, big_n);
    ASSERT_EQ(a.size(), big_n);
    const auto c = counts(a, n);
    for (std::size_t i = 0; i < n; ++i) {
      const double nw = static_cast<double>(big_n) * w[i];
      ASSERT_TRUE(c[i] == std::floor(nw) || c[i] == std::ceil(nw))
          << "trial " << trial << " particle " << i << ": " << c[i] << " copies for N w = " << nw;
    }
  }
}

TEST(Resampling, OutputIsSortedAndInRange) {
  Rng rng({.seed = 2, .step = 0, .index = 0, .purpose = purpose::kUser});
  for (auto scheme : kAllSchemes)
    for (int trial = 0; trial < 200; ++trial) {
      const std::size_t n = 1 + static_cast<std::size_t>(rng.uniform() * 40);
      const std::size_t big_n = 1 + static_cast<std::size_t>(rng.uniform() * 100);
      const auto w = random_weights(rng, n);
      const auto a = resample(scheme, w, uniforms(rng, scheme, big_n), big_n);
      ASSERT_EQ(a.size(), big_n);
      ASSERT_TRUE(std::is_sorted(a.begin(), a.end())) << to_string(scheme);
      for (std::size_t k : a) {
        ASSERT_LT(k, n);
        ASSERT_GT(w[k], 0.0) << to_string(scheme) << " picked a zero-weight particle";
      }
    }
}

TEST(Resampling, EqualWeightsSystematicKeepsEveryone) {
  const std::vector<double> w(100, 0.01);
  for (double u0 : {1e-12, 0.5, 1.0 - 1e-12}) {
    const std::vector<double> u = {u0};
    const auto a = resample(ResamplingScheme::kSystematic, w, u, 100);
    for (std::size_t k = 0; k < 100; ++k) ASSERT_EQ(a[k], k) << "u = " << u0;
  }
}

TEST(Resampling, ResidualDeterministicPartIsExact) {
  // N w_i all integers: the residual scheme is fully deterministic, whatever the uniforms.
  const std::vector<double> w = {0.5, 0.25, 0.25};
  Rng rng({.seed = 3, .step = 0, .index = 0, .purpose = purpose::kUser});
  for (int trial = 0; trial < 20; ++trial) {
    const auto a =
        resample(ResamplingScheme::kResidual, w, uniforms(rng, ResamplingScheme::kResidual, 4), 4);
    EXPECT_EQ(a, (std::vector<std::size_t>{0, 0, 1, 2}));
  }
  // Otherwise each particle gets at least floor(N w_i) copies and at most floor + (N - sum floor).
  for (int trial = 0; trial < 500; ++trial) {
    const std::size_t n = 1 + static_cast<std::size_t>(rng.uniform() * 30);
    const std::size_t big_n = 1 + static_cast<std::size_t>(rng.uniform() * 100);
    const auto w2 = random_weights(rng, n);
    const auto c = counts(resample(ResamplingScheme::kResidual, w2,
                                   uniforms(rng, ResamplingScheme::kResidual, big_n), big_n),
                          n);
    int floors = 0;
    for (std::size_t i = 0; i < n; ++i) floors += static_cast<int>(std::floor(big_n * w2[i]));
    const int rest = static_cast<int>(big_n) - floors;
    for (std::size_t i = 0; i < n; ++i) {
      const int f = static_cast<int>(std::floor(big_n * w2[i]));
      ASSERT_GE(c[i], f);
      ASSERT_LE(c[i], f + rest);
    }
  }
}

// Exact variance of particle i's count under each scheme (N outputs, weights w):
//   multinomial  N w (1 - w);
//   systematic   f (1 - f), f = frac(N w): the count is floor(N w) + Bernoulli(f);
//   stratified   sum_k p_k (1 - p_k), p_k = N |[k/N, (k+1)/N) ∩ [C_{i-1}, C_i)| (independent
//                strata each hit with probability p_k);
//   residual     R r (1 - r), R = N - sum_i floor(N w_i), r = frac(N w_i) / R (multinomial on
//                the residuals).
double count_variance(ResamplingScheme scheme, const std::vector<double>& w, std::size_t i,
                      std::size_t big_n) {
  const double n = static_cast<double>(big_n);
  switch (scheme) {
    case ResamplingScheme::kMultinomial:
      return n * w[i] * (1.0 - w[i]);
    case ResamplingScheme::kSystematic: {
      const double f = n * w[i] - std::floor(n * w[i]);
      return f * (1.0 - f);
    }
    case ResamplingScheme::kStratified: {
      double lo = 0.0;
      for (std::size_t k = 0; k < i; ++k) lo += w[k];
      const double hi = lo + w[i];
      double v = 0.0;
      for (std::size_t k = 0; k < big_n; ++k) {
        const double a = std::max(lo, k / n), b = std::min(hi, (k + 1) / n);
        const double p = b > a ? n * (b - a) : 0.0;
        v += p * (1.0 - p);
      }
      return v;
    }
    case ResamplingScheme::kResidual: {
      double rest = n;
      for (double x : w) rest -= std::floor(n * x);
      const double r = (n * w[i] - std::floor(n * w[i])) / rest;
      return rest * r * (1.0 - r);
    }
  }
  return 0.0;
}

TEST(Resampling, AllSchemesAreUnbiased) {
  // E[count_i] = N w_i for every scheme. Over R independent repetitions the mean count has
  // SE = sqrt(Var_i / R) with the scheme's exact variance (above); we allow 4.5 SE (failure
  // probability ~7e-6 per check, 52 checks). With R = 20000 the smallest detectable bias is
  // 4.5 sqrt(Var/R) <= 0.03 copies per particle.
  const std::size_t big_n = 30, reps = 20000;
  Rng wr({.seed = 4, .step = 0, .index = 0, .purpose = purpose::kUser});
  const auto w = random_weights(wr, 13);
  for (auto scheme : kAllSchemes) {
    std::vector<double> mean(w.size(), 0.0);
    for (std::size_t r = 0; r < reps; ++r) {
      Rng rng({.seed = 4, .step = r, .index = 0, .purpose = purpose::kResampling});
      const auto c = counts(resample(scheme, w, uniforms(rng, scheme, big_n), big_n), w.size());
      for (std::size_t i = 0; i < w.size(); ++i) mean[i] += c[i];
    }
    for (std::size_t i = 0; i < w.size(); ++i) {
      mean[i] /= reps;
      const double expected = big_n * w[i];
      const double se = std::sqrt(count_variance(scheme, w, i, big_n) / reps);
      if (w[i] == 0.0) {
        EXPECT_EQ(mean[i], 0.0) << to_string(scheme) << " particle " << i;
        continue;
      }
      EXPECT_LE(std::abs(mean[i] - expected), 4.5 * se)
          << to_string(scheme) << " particle " << i << ": mean count " << mean[i] << " vs N w "
          << expected << " (SE " << se << ")";
    }
  }
}

TEST(Resampling, SystematicHasLowerVarianceThanMultinomial) {
  // A sanity property of the variance formulas used above (not of the code under test):
  // for every particle, Var_systematic, Var_stratified, Var_residual <= Var_multinomial.
  Rng wr({.seed = 5, .step = 0, .index = 0, .purpose = purpose::kUser});
  const auto w = random_weights(wr, 17);
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double vm = count_variance(ResamplingScheme::kMultinomial, w, i, 40);
    for (auto s : {ResamplingScheme::kSystematic, ResamplingScheme::kStratified,
                   ResamplingScheme::kResidual})
      EXPECT_LE(count_variance(s, w, i, 40), vm + 1e-12) << to_string(s) << " particle " << i;
  }
}

TEST(Resampling, RngOverloadUsesTheSameUniforms) {
  Rng wr({.seed = 6, .step = 0, .index = 0, .purpose = purpose::kUser});
  const auto w = random_weights(wr, 10);
  for (auto scheme : kAllSchemes) {
    Rng a({.seed = 6, .step = 1, .index = 0, .purpose = purpose::kResampling});
    Rng b({.seed = 6, .step = 1, .index = 0, .purpose = purpose::kResampling});
    EXPECT_EQ(resample(scheme, w, 25, a), resample(scheme, w, uniforms(b, scheme, 25), 25));
  }
}

TEST(Resampling, OutputOverloadReusesTheVector) {
  // The out-parameter overload gives the same ancestors and clears what was there before.
  Rng wr({.seed = 7, .step = 0, .index = 0, .purpose = purpose::kUser});
  const auto w = random_weights(wr, 12);
  std::vector<std::size_t> out = {99, 98, 97};
  for (auto scheme : kAllSchemes) {
    const auto u = uniforms(wr, scheme, 20);
    resample(scheme, w, u, 20, out);
    EXPECT_EQ(out, resample(scheme, w, u, 20)) << to_string(scheme);
  }
}

TEST(Resampling, SchemeNamesRoundTrip) {
  for (auto scheme : kAllSchemes) EXPECT_EQ(parse_resampling_scheme(to_string(scheme)), scheme);
}

TEST(Resampling, EssTrigger) {
  // Resample exactly when ESS < threshold * M.
  EXPECT_TRUE(needs_resampling(49.9, 100, 0.5));
  EXPECT_FALSE(needs_resampling(50.0, 100, 0.5));
  EXPECT_FALSE(needs_resampling(0.0, 100, 0.0));    // threshold 0: never
  EXPECT_TRUE(needs_resampling(99.999, 100, 1.0));  // threshold 1: unless all weights equal
  EXPECT_FALSE(needs_resampling(100.0, 100, 1.0));
  // From weights: ESS of equal weights is M; of one dominant weight about 1.
  std::vector<double> lw(100, 0.0), w(100);
  EXPECT_FALSE(needs_resampling(normalize_log_weights(lw, w).ess, 100, 0.5));
  lw[7] = 50.0;
  EXPECT_TRUE(needs_resampling(normalize_log_weights(lw, w).ess, 100, 0.5));
}

}  // namespace
}  // namespace implicit

TEST(Weights, MomentsInOnePassMatchTheSeparateFunctions) {
  // weight_moments fuses log_mean_exp, the ESS of normalize_log_weights and
  // relative_standard_error; it must agree with each, including -inf entries and the edge cases.
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::vector<double>> cases = {
      {0.3, -1.2, 2.5, -700.0, 1.0}, {-inf, 4.0, 4.0, -2.0}, {12.0}, {-3.0, -3.0, -3.0}};
  for (const auto& lw : cases) {
    const auto m = implicit::weight_moments(lw);
    std::vector<double> w(lw.size());
    const auto s = implicit::normalize_log_weights(lw, w);
    EXPECT_NEAR(m.log_mean, implicit::log_mean_exp(lw), 1e-13 * (1.0 + std::abs(m.log_mean)));
    EXPECT_NEAR(m.ess, s.ess, 1e-12 * s.ess);
    const double se = implicit::relative_standard_error(lw);
    if (std::isfinite(se))
      EXPECT_NEAR(m.relative_se, se, 1e-12 * (1.0 + se));
    else
      EXPECT_EQ(m.relative_se, se);
  }
  const std::vector<double> dead = {-inf, -inf};
  const auto d = implicit::weight_moments(dead);
  EXPECT_EQ(d.log_mean, -inf);
  EXPECT_EQ(d.ess, 0.0);
  EXPECT_EQ(d.relative_se, inf);
  EXPECT_EQ(implicit::weight_moments(std::vector<double>{}).log_mean, -inf);
}
