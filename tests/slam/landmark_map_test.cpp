// Copy-on-write landmark maps: values, sharing, isolation of updates, memory.
#include <gtest/gtest.h>

#include <unordered_set>
#include <vector>

#include "implicit/slam/landmark_map.hpp"

namespace implicit::slam {
namespace {

LandmarkEstimate lm(double v) { return {Vec<2>(v, -v), Mat<2>::Identity() * v}; }

TEST(LandmarkEstimates, PushGetSetAcrossLevels) {
  LandmarkEstimates a;
  EXPECT_TRUE(a.empty());
  const int n = 1000;  // 8^3 < 1000 < 8^4: four levels of internal nodes
  for (int i = 0; i < n; ++i) a.push_back(lm(i));
  ASSERT_EQ(a.size(), static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) EXPECT_EQ(a.get(static_cast<std::size_t>(i)).mean(0), i);
  a.set(517, lm(-1));
  EXPECT_EQ(a.get(517).mean(0), -1);
  EXPECT_EQ(a.get(516).mean(0), 516);
  std::size_t visited = 0;
  a.for_each([&](std::size_t i, const LandmarkEstimate& l) {
    EXPECT_EQ(i, visited++);
    EXPECT_EQ(l.mean(0), i == 517 ? -1.0 : static_cast<double>(i));
  });
  EXPECT_EQ(visited, static_cast<std::size_t>(n));
  EXPECT_THROW(a.get(static_cast<std::size_t>(n)), InvalidArgument);
  EXPECT_THROW(a.set(static_cast<std::size_t>(n), lm(0)), InvalidArgument);
}

// The defining property: after sharing (what resampling does), an update through one handle
// leaves every other handle's map unchanged, and unchanged parts stay shared.
TEST(LandmarkEstimates, UpdateLeavesOtherParticlesUnchanged) {
  LandmarkEstimates parent;
  for (int i = 0; i < 300; ++i) parent.push_back(lm(i));
  std::vector<LandmarkEstimates> particles(10, parent);  // resampled copies
  for (const auto& p : particles) EXPECT_TRUE(p.shares_root_with(parent));
  particles[3].set(42, lm(1e6));
  particles[3].push_back(lm(7));
  particles[5].set(299, lm(-5));
  EXPECT_EQ(parent.get(42).mean(0), 42);
  EXPECT_EQ(parent.size(), 300u);
  for (std::size_t j = 0; j < particles.size(); ++j) {
    EXPECT_EQ(particles[j].get(42).mean(0), j == 3 ? 1e6 : 42.0);
    EXPECT_EQ(particles[j].get(299).mean(0), j == 5 ? -5.0 : 299.0);
    EXPECT_EQ(particles[j].size(), j == 3 ? 301u : 300u);
  }
  // Memory: 10 maps that differ in two paths cost about one map plus two paths, not ten maps.
  std::unordered_set<const void*> seen;
  std::size_t shared = 0;
  for (const auto& p : particles) shared += p.unique_bytes(seen);
  std::unordered_set<const void*> one;
  const std::size_t single = parent.unique_bytes(one);
  EXPECT_LT(shared, single + 3 * 4 * LandmarkEstimates::internal_bytes() +
                        3 * LandmarkEstimates::leaf_bytes());
  EXPECT_GT(shared, single);
}

TEST(LandmarkEstimates, EmptyMapAndSingleItem) {
  LandmarkEstimates a;
  std::unordered_set<const void*> seen;
  EXPECT_EQ(a.unique_bytes(seen), 0u);
  a.for_each([](std::size_t, const LandmarkEstimate&) { FAIL(); });
  EXPECT_THROW(a.get(0), InvalidArgument);
  a.push_back(lm(3));
  EXPECT_EQ(a.get(0).cov(1, 1), 3.0);
}

}  // namespace
}  // namespace implicit::slam
