// Randomness and determinism: the Rng streams, and bit-identical sample sets for any thread
// count and across runs.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "core/oracle_models.hpp"
#include "implicit/implicit.hpp"

namespace implicit {
namespace {

template <int N>
bool identical(const SampleSet<N>& a, const SampleSet<N>& b) {
  // Bitwise comparison: == on doubles would accept -0.0 == 0.0 and reject NaN == NaN.
  return a.size() == b.size() && a.x.size() == b.x.size() &&
         std::memcmp(a.log_weights.data(), b.log_weights.data(), a.size() * sizeof(double)) == 0 &&
         std::memcmp(a.weights.data(), b.weights.data(), a.size() * sizeof(double)) == 0 &&
         std::memcmp(a.x.data(), b.x.data(),
                     static_cast<std::size_t>(a.x.size()) * sizeof(double)) == 0 &&
         std::memcmp(&a.log_Z, &b.log_Z, sizeof(double)) == 0 &&
         std::memcmp(&a.ess, &b.ess, sizeof(double)) == 0;
}

template <typename Run>
void expect_thread_independent(Run run) {
  auto serial = [&] {
    ThreadLimit limit(1);
    return run();
  }();
  auto parallel = [&] {
    ThreadLimit limit(2);
    return run();
  }();
  auto again = [&] {
    ThreadLimit limit(2);
    return run();
  }();
  EXPECT_TRUE(identical(serial, parallel)) << "1 thread vs 2 threads";
  EXPECT_TRUE(identical(parallel, again)) << "two runs with 2 threads";
  // Spot check with == as well (memcmp could hide an empty comparison).
  ASSERT_GT(serial.size(), 0u);
  for (std::size_t j = 0; j < serial.size(); ++j)
    ASSERT_EQ(serial.log_weights[j], parallel.log_weights[j]) << "sample " << j;
}

TEST(Determinism, LinearMapSameBitsForAnyThreadCount) {
  const auto f = make_autodiff_target<6>(testing::T3Model{});
  expect_thread_independent([&] { return sample(f, Vec<6>::Zero(), 4000, {.seed = 9}); });
}

TEST(Determinism, RandomMapSameBitsForAnyThreadCount) {
  const auto f = make_autodiff_target<6>(testing::T3Model{});
  SamplerOptions o;
  o.map = MapKind::kRandom;
  expect_thread_independent([&] { return sample(f, Vec<6>::Zero(), 4000, {.seed = 9}, o); });
}

TEST(Determinism, DynamicSizeSameBitsForAnyThreadCount) {
  const auto f = make_autodiff_target<Eigen::Dynamic>(testing::T1Model{}, 3);
  SamplerOptions o;
  o.map = MapKind::kRandom;
  expect_thread_independent(
      [&] { return sample(f, Eigen::VectorXd::Zero(3), 3000, {.seed = 10}, o); });
}

TEST(Determinism, MixtureSameBitsForAnyThreadCount) {
  const auto f = make_autodiff_target<2>(testing::T4Model{});
  const MixtureProposal<2> q({Laplace<2>::make(Vec<2>(0.0, 0.0), 0.0, Mat<2>::Identity()),
                              Laplace<2>::make(Vec<2>(1.0, 0.5), 1.0, 2.0 * Mat<2>::Identity())});
  expect_thread_independent([&] { return sample_mixture(f, q, 3000, {.seed = 11}); });
}

TEST(Determinism, SerialOptionGivesSameBits) {
  const auto f = make_autodiff_target<2>(testing::T5Model{});
  SamplerOptions o;
  o.map = MapKind::kRandom;
  const auto a = sample(f, Vec<2>(1.0, 1.0), 2000, {.seed = 12}, o);
  o.parallel = false;
  const auto b = sample(f, Vec<2>(1.0, 1.0), 2000, {.seed = 12}, o);
  EXPECT_TRUE(identical(a, b));
}

TEST(Determinism, DifferentSeedsDiffer) {
  const auto f = make_autodiff_target<1>(testing::T2Model{});
  const auto a = sample(f, Vec<1>(0.0), 100, {.seed = 1});
  const auto b = sample(f, Vec<1>(0.0), 100, {.seed = 2});
  const auto c = sample(f, Vec<1>(0.0), 100, {.seed = 1, .step = 1});
  EXPECT_FALSE(identical(a, b));
  EXPECT_FALSE(identical(a, c));
}

// ---------------------------------------------------------------------------------------------
// Rng streams.

TEST(Rng, SameKeySameSequence) {
  Rng a({.seed = 3, .step = 4, .index = 5, .purpose = 6});
  Rng b({.seed = 3, .step = 4, .index = 5, .purpose = 6});
  for (int k = 0; k < 1000; ++k) {
    ASSERT_EQ(a.uniform(), b.uniform());
    ASSERT_EQ(a.normal(), b.normal());
  }
}

TEST(Rng, EveryKeyFieldSelectsADifferentStream) {
  const StreamKey base{.seed = 3, .step = 4, .index = 5, .purpose = 6};
  std::vector<StreamKey> keys = {base};
  for (int field = 0; field < 4; ++field) {
    StreamKey k = base;
    (field == 0 ? k.seed : field == 1 ? k.step : field == 2 ? k.index : k.purpose) += 1;
    keys.push_back(k);
  }
  std::vector<std::vector<double>> draws;
  for (const auto& k : keys) {
    Rng rng(k);
    std::vector<double> d(8);
    for (double& x : d) x = rng.uniform();
    draws.push_back(d);
  }
  for (std::size_t i = 0; i < draws.size(); ++i)
    for (std::size_t j = i + 1; j < draws.size(); ++j)
      for (std::size_t k = 0; k < 8; ++k)
        EXPECT_NE(draws[i][k], draws[j][k]) << "keys " << i << " and " << j << ", draw " << k;
  // Swapping step and index must not give the same stream either.
  Rng a({.seed = 1, .step = 2, .index = 3, .purpose = 4});
  Rng b({.seed = 1, .step = 3, .index = 2, .purpose = 4});
  EXPECT_NE(a.uniform(), b.uniform());
}

TEST(Rng, UniformMomentsAndRange) {
  // n = 1e6 uniforms: all in the open interval (0, 1); mean within 4.5 sqrt(1/12 / n) of 1/2;
  // variance within 4.5 sqrt(Var((U - 1/2)^2) / n) = 4.5 sqrt(1/180 / n) of 1/12.
  Rng rng({.seed = 21, .step = 0, .index = 0, .purpose = purpose::kUser});
  const int n = 1000000;
  double s1 = 0.0, s2 = 0.0, lo = 1.0, hi = 0.0;
  for (int k = 0; k < n; ++k) {
    const double u = rng.uniform();
    lo = std::min(lo, u);
    hi = std::max(hi, u);
    s1 += u;
    s2 += (u - 0.5) * (u - 0.5);
  }
  EXPECT_GT(lo, 0.0);
  EXPECT_LT(hi, 1.0);
  EXPECT_NEAR(s1 / n, 0.5, 4.5 * std::sqrt(1.0 / 12.0 / n));
  EXPECT_NEAR(s2 / n, 1.0 / 12.0, 4.5 * std::sqrt(1.0 / 180.0 / n));
}

TEST(Rng, UniformHistogramIsFlat) {
  // Chi-square over 50 equal bins with n = 5e5: 49 degrees of freedom, mean 49, sd ~9.9.
  // P(chi2_49 > 110) ~ 2e-6 (Wilson-Hilferty), so 110 is the threshold.
  Rng rng({.seed = 22, .step = 0, .index = 0, .purpose = purpose::kUser});
  const int n = 500000, bins = 50;
  std::vector<int> c(bins, 0);
  for (int k = 0; k < n; ++k) ++c[static_cast<int>(rng.uniform() * bins)];
  const double e = static_cast<double>(n) / bins;
  double chi2 = 0.0;
  for (int b : c) chi2 += (b - e) * (b - e) / e;
  EXPECT_LT(chi2, 110.0);
}

TEST(Rng, NormalMoments) {
  // n = 1e6 standard normals: mean within 4.5/sqrt(n); variance within 4.5 sqrt(2/n)
  // (Var(Z^2) = 2); fourth moment within 4.5 sqrt(96/n) of 3 (Var(Z^4) = 105 - 9); the
  // third moment within 4.5 sqrt(15/n) of 0.
  Rng rng({.seed = 23, .step = 0, .index = 0, .purpose = purpose::kUser});
  const int n = 1000000;
  double m1 = 0.0, m2 = 0.0, m3 = 0.0, m4 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double z = rng.normal();
    m1 += z;
    m2 += z * z;
    m3 += z * z * z;
    m4 += z * z * z * z;
  }
  EXPECT_NEAR(m1 / n, 0.0, 4.5 / std::sqrt(n));
  EXPECT_NEAR(m2 / n, 1.0, 4.5 * std::sqrt(2.0 / n));
  EXPECT_NEAR(m3 / n, 0.0, 4.5 * std::sqrt(15.0 / n));
  EXPECT_NEAR(m4 / n, 3.0, 4.5 * std::sqrt(96.0 / n));
}

TEST(Rng, NormalVectorUsesTheStream) {
  Rng a({.seed = 24});
  Rng b({.seed = 24});
  const Vec<5> v = a.normal_vector<5>();
  for (int i = 0; i < 5; ++i) EXPECT_EQ(v(i), b.normal());
  const Eigen::VectorXd d = a.normal_vector<Eigen::Dynamic>(7);
  EXPECT_EQ(d.size(), 7);
}

// Replaying after rewind() gives the stream's own sequence, whether the vectors were kept or
// (past max_kept) drawn again; odd sizes check that the cached second Box-Muller normal is kept
// in step too.
TEST(Rng, ReplayableNormalsReplayTheStream) {
  const implicit::StreamKey key{11, 2, 3, implicit::purpose::kReference};
  for (const std::size_t max_kept : {std::size_t{1} << 20, std::size_t{20}, std::size_t{0}}) {
    implicit::Rng rng(key);
    Eigen::VectorXd expected(7 * 5);
    rng.fill_normal(expected);
    implicit::ReplayableNormals replay(key, max_kept);
    Eigen::VectorXd xi(7);
    for (int pass = 0; pass < 3; ++pass) {
      replay.rewind();
      const int vectors = pass == 0 ? 3 : 5 - 2 * (pass - 1);  // 3, 5, 3: a pass past the last
      for (int j = 0; j < vectors; ++j) {
        replay.next(xi);
        for (int i = 0; i < 7; ++i)
          EXPECT_EQ(xi(i), expected(7 * j + i)) << "max_kept " << max_kept << " pass " << pass;
      }
    }
  }
}

TEST(Parallel, ForVisitsEveryIndexOnce) {
  for (std::size_t n : {0u, 1u, 15u, 16u, 17u, 1000u}) {
    std::vector<int> hits(n, 0);
    parallel_for(n, [&](std::size_t i) { ++hits[i]; });
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i], 1) << "n " << n << " index " << i;
  }
}

}  // namespace
}  // namespace implicit
