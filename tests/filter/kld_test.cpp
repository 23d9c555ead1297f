// KLD-sampling (Fox 2003): the bound against its closed form and against exact chi-square
// quantiles, the clamped count, and kld_resample's stopping rule, ancestor frequencies,
// determinism, input checks and heading wrapping.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/kld.hpp"

namespace implicit::filter {
namespace {

// Fox 2003 states the bound as n = chi2_{k-1, 1-delta} / (2 eps), with the chi-square quantile
// from the Wilson-Hilferty transformation chi2_{d, 1-delta} ~ d (1 - 2/(9d) + sqrt(2/(9d)) z)^3.
// Written again here from that statement, as quantile first, then divided.
double wilson_hilferty_quantile(double dof, double z) {
  const double v = 2.0 / (9.0 * dof);
  const double t = 1.0 - v + z * std::sqrt(v);
  return dof * t * t * t;
}
double paper_bound(int k, double eps, double z) {
  if (k <= 1) return 1.0;
  return wilson_hilferty_quantile(k - 1, z) / (2.0 * eps);
}

TEST(KldBound, MatchesThePaperClosedForm) {
  for (const auto& [eps, z] : {std::pair{0.01, 0.99}, std::pair{0.05, 2.326}}) {
    for (int k : {2, 3, 10, 100, 1000}) {
      const double expected = paper_bound(k, eps, z);
      EXPECT_NEAR(kld_bound(k, eps, z), expected, 1e-12 * expected)
          << "k=" << k << " eps=" << eps << " z=" << z;
    }
  }
  // Hand value: k = 2, eps = 0.05, z = 2.326: 1/(0.1) * (7/9 + sqrt(2/9) 2.326)^3.
  const double b = 7.0 / 9.0 + std::sqrt(2.0 / 9.0) * 2.326;
  EXPECT_NEAR(kld_bound(2, 0.05, 2.326), 10.0 * b * b * b, 1e-12);
}

TEST(KldBound, OneOrNoBinNeedsOneSample) {
  EXPECT_EQ(kld_bound(0, 0.01, 0.99), 1.0);
  EXPECT_EQ(kld_bound(1, 0.01, 0.99), 1.0);
  EXPECT_EQ(kld_bound(1, 0.5, 3.0), 1.0);
}

// Regularised lower incomplete gamma P(a, x), by its power series for x < a + 1 and by the
// continued fraction of Q = 1 - P otherwise (Lentz's method); accurate to ~1e-14 here.
double gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000 && std::abs(term) > 1e-17 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return sum * std::exp(log_prefactor);
  }
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

// The p quantile of chi-square(dof): the CDF P(dof/2, x/2) inverted by bisection.
double chi_square_quantile(double dof, double p) {
  double lo = 0.0, hi = dof + 100.0 * std::sqrt(dof) + 100.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (gamma_p(0.5 * dof, 0.5 * mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(KldBound, ApproximatesTheExactChiSquareQuantile) {
  // Known values check the quantile routine itself: chi2(1) 0.99 quantile = 2.5758293035^2
  // (the square of the normal quantile), chi2(2) p-quantile = -2 ln(1 - p).
  EXPECT_NEAR(chi_square_quantile(1.0, 0.99), 2.5758293035489 * 2.5758293035489, 1e-9);
  EXPECT_NEAR(chi_square_quantile(2.0, 0.99), -2.0 * std::log(0.01), 1e-9);
  // With z the exact upper 0.01 normal quantile, 2 eps n(k) is Wilson-Hilferty's approximation
  // of the 0.99 quantile of chi-square(k-1), which is good to about 1e-3 relative already at ten
  // degrees of freedom: 2e-3 is that bound with a factor of 2 of margin, not a fitted value. The
  // approximation improves with the degrees of freedom, so the error must also shrink with k.
  const double z = 2.3263478740408408;  // Phi^{-1}(0.99)
  const double eps = 0.05;
  double previous_error = 1.0;
  for (int k : {10, 100, 1000}) {
    const double exact = chi_square_quantile(k - 1, 0.99);
    const double error = std::abs(2.0 * eps * kld_bound(k, eps, z) / exact - 1.0);
    EXPECT_LT(error, 2e-3) << "k=" << k << " exact quantile " << exact;
    EXPECT_LT(error, previous_error) << "k=" << k;
    previous_error = error;
    std::printf("k=%d: exact chi2(%d) 0.99 quantile %.6f, relative error of 2 eps n(k) %.2e\n", k,
                k - 1, exact, error);
  }
}

TEST(KldBound, GrowsLikeDofOverTwoEpsilon) {
  // n(k) / ((k-1)/(2 eps)) = (1 - 2/(9d) + sqrt(2/(9d)) z)^3 -> 1 as d = k-1 grows; the leading
  // deviation is 3 z sqrt(2/(9d)) = sqrt(2) z / sqrt(d).
  const double eps = 0.05, z = 2.326;
  for (double k : {1e4, 1e6, 1e8, 1e10}) {
    const double d = k - 1.0;
    const double ratio = kld_bound(static_cast<std::size_t>(k), eps, z) / (d / (2.0 * eps));
    EXPECT_GT(ratio, 1.0);
    EXPECT_NEAR(ratio - 1.0, std::sqrt(2.0) * z / std::sqrt(d), 2.0 * z * z / d) << "k=" << k;
  }
}

TEST(KldBound, MonotoneInBinsErrorAndQuantile) {
  for (double z : {0.0, 0.99, 2.326, 3.09}) {
    for (double eps : {0.01, 0.05, 0.2}) {
      double previous = kld_bound(1, eps, z);
      for (std::size_t k = 2; k <= 3000; ++k) {
        const double n = kld_bound(k, eps, z);
        ASSERT_GT(n, previous) << "k=" << k << " eps=" << eps << " z=" << z;
        previous = n;
      }
    }
  }
  for (std::size_t k : {2, 10, 100, 1000}) {
    EXPECT_GT(kld_bound(k, 0.01, 0.99), kld_bound(k, 0.02, 0.99)) << "smaller eps, more";
    EXPECT_GT(kld_bound(k, 0.05, 2.326), kld_bound(k, 0.05, 0.99)) << "larger z, more";
  }
}

TEST(KldParticleCount, CeilOfTheBoundClampedToMinAndMax) {
  KldOptions o;  // eps 0.01, z 0.99, min 100, max 5000
  EXPECT_EQ(kld_particle_count(0, o), 100u);
  EXPECT_EQ(kld_particle_count(1, o), 100u);
  // k = 2: 50 (7/9 + sqrt(2/9) 0.99)^3 = 50 * 1.2445^3 ~ 96 < 100: still the minimum.
  EXPECT_LT(kld_bound(2, o.kld_err, o.kld_z), 100.0);
  EXPECT_EQ(kld_particle_count(2, o), 100u);
  for (std::size_t k : {3, 10, 50}) {
    const double n = paper_bound(static_cast<int>(k), o.kld_err, o.kld_z);
    ASSERT_GT(n, 100.0);
    ASSERT_LT(n, 5000.0);
    EXPECT_EQ(kld_particle_count(k, o), static_cast<std::size_t>(std::ceil(n))) << "k=" << k;
  }
  EXPECT_GT(kld_bound(200, o.kld_err, o.kld_z), 5000.0);
  EXPECT_EQ(kld_particle_count(200, o), 5000u);
  EXPECT_EQ(kld_particle_count(std::numeric_limits<std::size_t>::max(), o), 5000u);
  // A negative z can make the bound negative: still the minimum, not a wrapped conversion.
  o.kld_z = -10.0;
  EXPECT_LT(kld_bound(3, o.kld_err, o.kld_z), 0.0);
  EXPECT_EQ(kld_particle_count(3, o), 100u);
  o.min_particles = o.max_particles = 7;
  EXPECT_EQ(kld_particle_count(1000, o), 7u);
}

Rng resampling_rng(std::uint64_t seed) {
  return Rng({.seed = seed, .step = 3, .index = 0, .purpose = purpose::kResampling});
}

// Bins recomputed independently of the library's hashing: the exact index triples.
std::size_t occupied_bins(const std::vector<std::size_t>& ancestors, const std::vector<Pose>& p,
                          const KldOptions& o) {
  std::set<std::tuple<long long, long long, long long>> bins;
  for (std::size_t i : ancestors) {
    double h = std::remainder(p[i](2), 2.0 * kPi);  // in [-pi, pi]
    if (h >= kPi) h -= 2.0 * kPi;
    bins.emplace(static_cast<long long>(std::floor(p[i](0) / o.bin_xy)),
                 static_cast<long long>(std::floor(p[i](1) / o.bin_xy)),
                 static_cast<long long>(std::floor(h / o.bin_heading)));
  }
  return bins.size();
}

TEST(KldResample, OneBinGivesExactlyTheMinimum) {
  KldOptions o{.enabled = true, .min_particles = 137};
  // 50 distinct poses inside one 0.5 m x 0.5 m x 10 degree bin.
  std::vector<Pose> p;
  std::vector<double> w;
  for (int i = 0; i < 50; ++i) {
    p.emplace_back(1.01 + 0.009 * i, 2.02 + 0.009 * i, 0.001 * i);
    w.push_back(1.0 + i);
  }
  Rng rng = resampling_rng(1);
  const auto a = kld_resample(w, p, o, rng);
  EXPECT_EQ(a.size(), 137u);
  EXPECT_EQ(occupied_bins(a, p, o), 1u);
  for (std::size_t i : a) EXPECT_LT(i, p.size());
}

// M particles, one per bin along x, equal weights.
std::vector<Pose> one_per_bin(int m, const KldOptions& o) {
  std::vector<Pose> p;
  for (int i = 0; i < m; ++i) p.emplace_back((i + 0.5) * o.bin_xy, -0.25 * o.bin_xy, 0.05);
  return p;
}

TEST(KldResample, StopsAtTheBoundOfTheBinsItOccupied) {
  // (eps, z, M): the stop mid-way while new bins still appear (eps 0.25: n(k) ~ 2k, so it stops
  // near 1.6 M draws with ~80 % of the bins occupied), after all bins are occupied (eps 0.05,
  // M 200: n(200) ~ 2480), and at the maximum (defaults, M 2000: n(2000) ~ 1e5 > 5000).
  struct Case {
    double eps, z;
    int m;
  };
  for (const Case& c : {Case{0.25, 0.99, 1000}, Case{0.05, 2.326, 200}, Case{0.01, 0.99, 2000}}) {
    KldOptions o{.enabled = true, .kld_err = c.eps, .kld_z = c.z};
    const std::vector<Pose> p = one_per_bin(c.m, o);
    const std::vector<double> w(p.size(), 1.0);
    for (std::uint64_t seed : {1, 2, 3}) {
      Rng rng = resampling_rng(seed);
      const auto a = kld_resample(w, p, o, rng);
      const std::size_t k = occupied_bins(a, p, o);
      std::printf("eps %.2f z %.3f M %d seed %d: %zu draws, %zu bins\n", c.eps, c.z, c.m,
                  static_cast<int>(seed), a.size(), k);
      // The count reached when the loop stopped is the count for the bins occupied then: it grows
      // with k, so the first n with n >= count(k_n) satisfies it with equality.
      EXPECT_EQ(a.size(), kld_particle_count(k, o))
          << "M=" << c.m << " seed=" << seed << " k=" << k;
      EXPECT_LE(a.size(), o.max_particles);
      EXPECT_GE(a.size(), o.min_particles);
      if (c.m == 2000) {
        EXPECT_EQ(a.size(), o.max_particles);
      } else if (c.m == 1000) {
        EXPECT_LT(k, 1000u) << "should stop before every bin is occupied";
      } else {
        // ~2480 equiprobable draws over 200 bins leave one empty with probability
        // 200 exp(-2480/200) < 1e-3 per seed.
        EXPECT_EQ(k, 200u);
      }
    }
  }
}

TEST(KldResample, AncestorFrequenciesMatchTheWeights) {
  // A fixed count (min = max = 20000) so only the ancestor draws vary. Pearson's statistic over
  // the 4 positive-weight cells is asymptotically chi-square(3) for correct i.i.d. draws; 16.27
  // is its 0.999 quantile, so a correct sampler fails this seed-fixed check with probability
  // 0.001. The zero weight must never be drawn; weights are deliberately not normalised.
  KldOptions o{.enabled = true, .min_particles = 20000, .max_particles = 20000};
  const std::vector<double> w = {0.5, 0.0, 1.0, 3.0, 0.5e1};
  const std::vector<Pose> p = one_per_bin(static_cast<int>(w.size()), o);
  Rng rng = resampling_rng(11);
  const auto a = kld_resample(w, p, o, rng);
  ASSERT_EQ(a.size(), 20000u);
  std::vector<double> counts(w.size(), 0.0);
  for (std::size_t i : a) counts.at(i) += 1.0;
  EXPECT_EQ(counts[1], 0.0);
  const double total = 9.5;
  double chi2 = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    if (w[i] == 0.0) continue;
    const double expected = 20000.0 * w[i] / total;
    chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
  }
  std::printf("Pearson statistic over 20000 draws: %.3f (threshold 16.27)\n", chi2);
  EXPECT_LT(chi2, 16.27);
}

TEST(KldResample, SameKeySameResultDifferentKeyDifferent) {
  KldOptions o{.enabled = true, .kld_err = 0.25};
  const std::vector<Pose> p = one_per_bin(500, o);
  std::vector<double> w;
  for (std::size_t i = 0; i < p.size(); ++i) w.push_back(1.0 + static_cast<double>(i % 7));
  Rng r1 = resampling_rng(5), r2 = resampling_rng(5), r3 = resampling_rng(6);
  const auto a1 = kld_resample(w, p, o, r1);
  const auto a2 = kld_resample(w, p, o, r2);
  const auto a3 = kld_resample(w, p, o, r3);
  EXPECT_EQ(a1, a2);
  EXPECT_NE(a1, a3);
  // The stream continues where the draws stopped, as for any consumer of an Rng.
  EXPECT_EQ(r1.uniform(), r2.uniform());
}

// Runs f, expects InvalidArgument, and returns its message.
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InvalidArgument thrown";
  return "";
}

TEST(KldResample, BadInputNamesTheProblem) {
  const KldOptions o{.enabled = true};
  const std::vector<Pose> p = one_per_bin(3, o);
  Rng rng = resampling_rng(1);
  auto run = [&](std::vector<double> w, std::vector<Pose> q, KldOptions opt) {
    return error_of([&] { kld_resample(w, q, opt, rng); });
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NE(run({0, 0, 0}, p, o).find("positive finite sum"), std::string::npos);
  EXPECT_NE(run({1, nan, 1}, p, o).find("weights[1]"), std::string::npos);
  EXPECT_NE(run({1, 1, inf}, p, o).find("weights[2]"), std::string::npos);
  EXPECT_NE(run({1, -1, 1}, p, o).find("weights[1]"), std::string::npos);
  EXPECT_NE(run({1e308, 1e308, 1e308}, p, o).find("positive finite sum"), std::string::npos);
  EXPECT_NE(run({1, 1}, p, o).find("as many weights as particles (3), got 2"), std::string::npos);
  EXPECT_NE(run({}, {}, o).find("at least one weight"), std::string::npos);
  std::vector<Pose> bad = p;
  bad[2](1) = nan;
  EXPECT_NE(run({1, 1, 1}, bad, o).find("particles[2]"), std::string::npos);
  EXPECT_NO_THROW(kld_resample(std::vector<double>{1, 1, 0}, bad, o, rng)) << "weight 0: unused";

  struct BadOption {
    KldOptions o;
    const char* field;
  };
  const std::vector<BadOption> cases = {
      {{.kld_err = 0.0}, "kld_err"},
      {{.kld_err = -0.1}, "kld_err"},
      {{.kld_err = nan}, "kld_err"},
      {{.kld_z = nan}, "kld_z"},
      {{.kld_z = inf}, "kld_z"},
      {{.min_particles = 0}, "min_particles"},
      {{.min_particles = 10, .max_particles = 9}, "min_particles"},
      {{.bin_xy = 0.0}, "bin_xy"},
      {{.bin_xy = inf}, "bin_xy"},
      {{.bin_heading = -1.0}, "bin_heading"},
      {{.bin_heading = nan}, "bin_heading"},
  };
  for (const BadOption& c : cases) {
    EXPECT_NE(error_of([&] { validate(c.o); }).find(std::string("KldOptions.") + c.field),
              std::string::npos)
        << c.field;
    EXPECT_NE(run({1, 1, 1}, p, c.o).find(c.field), std::string::npos) << c.field;
  }
  EXPECT_NO_THROW(validate(KldOptions{}));
}

TEST(KldResample, HeadingsTwoPiApartShareABin) {
  KldOptions o{.enabled = true, .min_particles = 40};
  // Same (x, y); headings pi + 0.01 and -pi + 0.01 are one direction: one bin, the minimum.
  const std::vector<Pose> same = {Pose(0.1, 0.1, kPi + 0.01), Pose(0.1, 0.1, -kPi + 0.01),
                                  Pose(0.1, 0.1, 3.0 * kPi + 0.01)};
  const std::vector<double> w(3, 1.0);
  Rng rng = resampling_rng(2);
  const auto a = kld_resample(w, same, o, rng);
  EXPECT_EQ(a.size(), 40u);
  std::set<std::size_t> drawn(a.begin(), a.end());
  EXPECT_EQ(drawn.size(), 3u) << "all three poses are drawn, yet they occupy one bin";
  // Control: headings pi - 0.01 and -pi + 0.01 are in different bins (the last and the first),
  // so the count is that of two bins.
  const std::vector<Pose> apart = {Pose(0.1, 0.1, kPi - 0.01), Pose(0.1, 0.1, -kPi + 0.01)};
  Rng rng2 = resampling_rng(2);
  const auto b = kld_resample(std::vector<double>(2, 1.0), apart, o, rng2);
  EXPECT_EQ(occupied_bins(b, apart, o), 2u);
  EXPECT_EQ(b.size(), kld_particle_count(2, o));
  EXPECT_GT(b.size(), 40u);
}

}  // namespace
}  // namespace implicit::filter
