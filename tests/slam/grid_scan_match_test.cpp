// Scan matching against a particle's own map (slam/grid/scan_match.hpp, spec §3.13.1): the value
// on a one-beam map worked out by hand, the gradient and Hessian against finite differences on a
// mapped room, the Gauss-Newton matrix's sign, the beams used, and refused input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/scan_simulation.hpp"
#include "implicit/slam/grid/scan_match.hpp"
#include "implicit/slam/grid/tiled_grid.hpp"
#include "robot/laser_fixtures.hpp"

namespace implicit::slam {
namespace {

using robot::LaserScan;
using robot::Mat3;
using robot::Pose;

// One beam east from (0.5, 0.5) at 1 m cells: cells 0, 1, 2 of row 0 free, cell 3 hit.
LaserScan scan_match_one_beam(double range) {
  LaserScan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 0.1;
  scan.range_max = 10.0;
  scan.ranges = {range};
  return scan;
}

TEST(GridScanMatch, ValueOnAOneBeamMapWorkedOutByHand) {
  robot::GridMappingOptions opt;
  opt.resolution = 1.0;
  TiledLogOddsGrid map(opt);
  map.integrate(Pose(0.5, 0.5, 0.0), {}, scan_match_one_beam(3.0));
  ScanMatchParams p;
  p.smoothing = 1;
  p.floor = 0.1;
  const GridScanModel model(map, p);
  // An unobserved area has no occupancy evidence: M = 0, and a beam ending there costs -log eps.
  EXPECT_EQ(model.smoothed_occupancy(Vec<2>(40.3, -17.9)), 0.0);
  // At the hit cell's centre the cubic B-spline weights are 1/6, 2/3, 1/6 per axis; of the nine
  // cells only the hit cell has evidence, 2 P - 1 = tanh(0.85 / 2) (the crossed cell west of it
  // is free, the rest unobserved).
  const double m = 4.0 / 9.0 * std::tanh(0.425);
  EXPECT_NEAR(model.smoothed_occupancy(Vec<2>(3.5, 0.5)), m, 1e-7);
  EXPECT_NEAR(model.smoothed_occupancy(Vec<2>(3.0, 0.5)),
              2.0 / 3.0 * 23.0 / 48.0 * std::tanh(0.425),
              1e-7);  // between cells 2 and 3: weights 1/48, 23/48, 23/48, 1/48 along x
  const ScanMatchBeams beams = model.prepare(scan_match_one_beam(3.0));
  ASSERT_EQ(beams.size(), 1u);
  EXPECT_NEAR(model.log_likelihood(beams, Pose(0.5, 0.5, 0.0)), std::log(0.1 + 0.9 * m), 1e-7);
  // The same beam seen from a pose turned by pi/2 ends at (0.5, 3.5): never observed.
  EXPECT_NEAR(model.log_likelihood(beams, Pose(0.5, 0.5, kPi / 2)), std::log(0.1), 1e-12);
}

struct ScanMatchRoom {
  robot::OccupancyGrid truth = testing::laser_room(8.0, 6.0, 0.05);
  TiledLogOddsGrid map{robot::GridMappingOptions{}};
  LaserScan scan;
  ScanMatchRoom() {
    robot::ScanSimulationOptions sim;
    sim.range_max = 12.0;
    Rng rng({.seed = 21, .purpose = purpose::kData});
    for (const Pose& x : {Pose(1.2, 1.0, 0.0), Pose(5.5, 2.0, 1.5), Pose(4.0, 4.5, -2.8)})
      map.integrate(x, {}, robot::simulate_scan(truth, x, {}, sim, rng));
    scan = robot::simulate_scan(truth, Pose(1.9, 1.4, 0.3), {}, sim, rng);
  }
};

TEST(GridScanMatch, GradientAndHessianMatchFiniteDifferences) {
  const ScanMatchRoom room;
  ScanMatchParams p;
  p.max_beams = 30;
  const GridScanModel model(room.map, p, robot::LaserMount{0.1, -0.05, 0.02});
  const ScanMatchBeams beams = model.prepare(room.scan);
  ASSERT_EQ(beams.size(), 30u);
  for (const Pose& x : {Pose(1.9, 1.4, 0.3), Pose(1.93, 1.37, 0.32), Pose(2.1, 1.2, 0.1)}) {
    Vec<3> g = Vec<3>::Zero();
    Mat3 h = Mat3::Zero(), gn = Mat3::Zero();
    const double f = model.negative_log_likelihood(beams, x, &g, &h, &gn);
    EXPECT_NEAR(f, -model.log_likelihood(beams, x), 1e-12);
    const double step = 1e-6;
    for (int k = 0; k < 3; ++k) {
      Pose a = x, b = x;
      a(k) += step;
      b(k) -= step;
      const double fd = (model.negative_log_likelihood(beams, a, nullptr, nullptr, nullptr) -
                         model.negative_log_likelihood(beams, b, nullptr, nullptr, nullptr)) /
                        (2 * step);
      EXPECT_NEAR(g(k), fd, 1e-5 * (1.0 + std::abs(fd))) << "gradient " << k;
      Vec<3> ga = Vec<3>::Zero(), gb = Vec<3>::Zero();
      model.negative_log_likelihood(beams, a, &ga, nullptr, nullptr);
      model.negative_log_likelihood(beams, b, &gb, nullptr, nullptr);
      const Vec<3> column = (ga - gb) / (2 * step);
      for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(h(i, k), column(i), 1e-4 * (1.0 + std::abs(column(i)))) << i << "," << k;
    }
    EXPECT_LT((h - h.transpose()).norm(), 1e-9);
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(gn);
    EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff());
  }
}

TEST(GridScanMatch, TheLikelihoodPeaksNearTheTruePose) {
  const ScanMatchRoom room;
  const GridScanModel model(room.map, ScanMatchParams{});
  const ScanMatchBeams beams = model.prepare(room.scan);
  const Pose truth(1.9, 1.4, 0.3);
  const double at_truth = model.log_likelihood(beams, truth);
  // 10 cm or 0.1 rad away every beam moves by two cells or more: a clearly lower likelihood.
  for (int k = 0; k < 3; ++k)
    for (double sign : {-1.0, 1.0}) {
      Pose x = truth;
      x(k) += sign * 0.1;
      EXPECT_LT(model.log_likelihood(beams, x), at_truth - 5.0) << k << " " << sign;
    }
}

TEST(GridScanMatch, UsesEvenlySpacedHitsAndSkipsNoReturn) {
  TiledLogOddsGrid map{robot::GridMappingOptions{}};
  ScanMatchParams p;
  p.max_beams = 3;
  const GridScanModel model(map, p);
  LaserScan scan = scan_match_one_beam(1.0);
  scan.angle_increment = kPi / 2;
  scan.ranges = {1.0, 10.0, 2.0, std::numeric_limits<double>::infinity(), 3.0, 4.0};
  // Hits: beams 0, 2, 4, 5 (ranges 1, 2, 3, 4); three evenly spaced of four: hits 0, 2, 3.
  const ScanMatchBeams beams = model.prepare(scan);
  ASSERT_EQ(beams.size(), 3u);
  EXPECT_NEAR(beams.end_points[0].x(), 1.0, 1e-12);
  EXPECT_NEAR(beams.end_points[1].x(), 3.0 * std::cos(2 * kPi), 1e-12);
  EXPECT_NEAR(beams.end_points[2].y(), 4.0 * std::sin(5 * kPi / 2), 1e-12);
  scan.ranges = {10.0, std::numeric_limits<double>::infinity()};
  EXPECT_EQ(model.prepare(scan).size(), 0u);
  EXPECT_EQ(model.log_likelihood(model.prepare(scan), Pose(1, 2, 3)), 0.0);
}

TEST(GridScanMatch, RefusesInvalidInputNamingIt) {
  TiledLogOddsGrid map{robot::GridMappingOptions{}};
  const auto message = [&](ScanMatchParams p) {
    try {
      GridScanModel model(map, p);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ScanMatchParams p;
  p.max_beams = 0;
  EXPECT_NE(message(p).find("max_beams"), std::string::npos);
  p = {};
  p.floor = 0.0;
  EXPECT_NE(message(p).find("floor"), std::string::npos);
  p.floor = std::nan("");
  EXPECT_NE(message(p).find("floor"), std::string::npos);
  p = {};
  p.smoothing = 5;
  EXPECT_NE(message(p).find("smoothing"), std::string::npos);
  p = {};
  p.max_range = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(p).find("max_range"), std::string::npos);
  EXPECT_THROW(GridScanModel(map, ScanMatchParams{}, robot::LaserMount{std::nan(""), 0, 0}),
               InvalidArgument);
  const GridScanModel model(map, ScanMatchParams{});
  LaserScan empty = scan_match_one_beam(1.0);
  empty.ranges.clear();
  try {
    model.prepare(empty, "scan 7");
    ADD_FAILURE() << "an empty scan was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("scan 7"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace implicit::slam
