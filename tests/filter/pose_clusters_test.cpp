// The heaviest cluster of a weighted pose cloud (filter/pose_clusters.hpp): the cluster found is
// the heavier of two separated blobs with its exact weighted mean, neighbouring cells join across
// the heading wrap at +-pi, the result does not depend on the particle order, and bad input is
// refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/pose_clusters.hpp"
#include "refusal.hpp"

namespace implicit::filter {
namespace {

using robot::Pose;

// Two blobs 10 m apart, each within +-0.2 m and +-0.1 rad of its centre (cells of 0.5 m and
// 10 degrees join each blob and cannot bridge the gap). The weighted mean of all particles lies
// between them; the heaviest cluster's mean is the weighted mean of the heavier blob, computed
// here directly.
TEST(PoseClusters, TheHeavierOfTwoBlobsWithItsExactWeightedMean) {
  Rng rng({.seed = 3, .purpose = purpose::kUser});
  std::vector<Pose> xs;
  std::vector<double> w;
  double sw = 0, sx = 0, sy = 0, sh = 0;
  for (int j = 0; j < 400; ++j) {
    const bool heavy = j % 2 == 1;
    const double dx = 0.4 * rng.uniform() - 0.2;
    const double dy = 0.4 * rng.uniform() - 0.2;
    const double dh = 0.2 * rng.uniform() - 0.1;
    const double weight = (heavy ? 1.5 : 1.0) * (0.5 + rng.uniform());
    const Pose x = heavy ? Pose(12.0 + dx, 3.0 + dy, 1.0 + dh) : Pose(2.0 + dx, 3.0 + dy, dh);
    xs.push_back(x);
    w.push_back(weight);
    if (heavy) {
      sw += weight;
      sx += weight * x(0);
      sy += weight * x(1);
      sh += weight * x(2);
    }
  }
  double total = 0;
  for (double v : w) total += v;
  const PoseCluster c = heaviest_cluster(xs, w);
  EXPECT_EQ(c.clusters, 2u);
  EXPECT_EQ(c.particles, 200u);
  EXPECT_NEAR(c.weight, sw / total, 1e-12);
  EXPECT_NEAR(c.mean(0), sx / sw, 1e-12);
  EXPECT_NEAR(c.mean(1), sy / sw, 1e-12);
  // Headings within +-0.1 rad: the direction of the mean unit vector differs from the plain
  // weighted mean by O(0.1^3) at most.
  EXPECT_NEAR(c.mean(2), sh / sw, 1e-3);
  // The other order of the particles gives the same cluster, up to summation order.
  std::vector<Pose> rx(xs.rbegin(), xs.rend());
  std::vector<double> rw(w.rbegin(), w.rend());
  const PoseCluster r = heaviest_cluster(rx, rw);
  EXPECT_EQ(r.particles, c.particles);
  EXPECT_NEAR((r.mean - c.mean).norm(), 0.0, 1e-12);
}

// Particles at headings just below +pi and just above -pi are neighbours: one cluster whose mean
// heading is pi (not 0, where the arithmetic mean of the headings would put it).
TEST(PoseClusters, HeadingsJoinAcrossTheWrapAndAverageAsDirections) {
  const std::vector<Pose> xs = {Pose(0.1, 0.1, kPi - 0.05), Pose(0.1, 0.1, -kPi + 0.05)};
  const std::vector<double> w = {1.0, 1.0};
  const PoseCluster c = heaviest_cluster(xs, w);
  EXPECT_EQ(c.clusters, 1u);
  EXPECT_EQ(c.particles, 2u);
  EXPECT_NEAR(std::abs(c.mean(2)), kPi, 1e-12);
  // Half a turn apart in heading, same place: two clusters.
  const std::vector<Pose> apart = {Pose(0.1, 0.1, 0.0), Pose(0.1, 0.1, kPi / 2)};
  EXPECT_EQ(heaviest_cluster(apart, w).clusters, 2u);
}

// Cells chain: particles 0.4 m apart along a line are one cluster over 4 m (cells of 0.5 m touch),
// while a 1.2 m gap (an empty cell between) splits them. A tie in weight goes to the cluster with
// the first particle.
TEST(PoseClusters, NeighbouringCellsChainAndAnEmptyCellSplits) {
  std::vector<Pose> xs;
  for (int k = 0; k < 10; ++k) xs.emplace_back(0.05 + 0.4 * k, 0.2, 0.0);
  std::vector<double> w(xs.size(), 1.0);
  EXPECT_EQ(heaviest_cluster(xs, w).clusters, 1u);
  const std::vector<Pose> split = {Pose(0.2, 0.2, 0.0), Pose(1.4, 0.2, 0.0)};
  const std::vector<double> tie = {1.0, 1.0};
  const PoseCluster c = heaviest_cluster(split, tie);
  EXPECT_EQ(c.clusters, 2u);
  EXPECT_DOUBLE_EQ(c.mean(0), 0.2);
}

using implicit::test_support::expect_refused;

TEST(PoseClusters, RefusesBadInputByName) {
  const std::vector<Pose> one = {Pose(0, 0, 0)};
  const std::vector<double> w1 = {1.0};
  expect_refused([&] { heaviest_cluster(one, std::vector<double>{}); }, "one weight per pose");
  expect_refused([&] { heaviest_cluster(std::vector<Pose>{}, std::vector<double>{}); },
                 "at least one pose");
  expect_refused([&] { heaviest_cluster(one, w1, {.cell_m = 0.0}); }, "cells of positive size");
  expect_refused([&] { heaviest_cluster(one, w1, {.cell_m = 0.5, .cell_rad = 4.0}); },
                 "at most pi");
  expect_refused([&] { heaviest_cluster(one, std::vector<double>{-1.0}); }, "weight 0 is -1");
  expect_refused([&] { heaviest_cluster(one, std::vector<double>{std::nan("")}); }, "weight 0");
  expect_refused([&] { heaviest_cluster(one, std::vector<double>{0.0}); }, "every weight is zero");
  expect_refused([&] { heaviest_cluster(std::vector<Pose>{Pose(0, std::nan(""), 0)}, w1); },
                 "pose 0 is not finite");
  expect_refused([&] { heaviest_cluster(std::vector<Pose>{Pose(1e300, 0, 0)}, w1); },
                 "pose 0 is outside");
}

}  // namespace
}  // namespace implicit::filter
