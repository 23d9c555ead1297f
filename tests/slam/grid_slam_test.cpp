// Grid SLAM (slam/grid/grid_slam.hpp, spec §3.13): the three proposals recover a simulated drive
// in a known room, the implicit weights are exact (their mean against Z by quadrature), the
// results do not depend on the thread count, and bad input is refused naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/scan_simulation.hpp"
#include "implicit/slam/grid/grid_proposals.hpp"
#include "implicit/slam/grid/grid_slam.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "robot/laser_fixtures.hpp"

namespace implicit::slam {
namespace {

using robot::LaserScan;
using robot::Pose;

// Odometry noise of the drive: per 0.3 m step a translation sd of sqrt(0.02) * 0.3 = 4 cm and a
// rotation sd of about 2.4 degrees, so dead reckoning drifts by decimetres over the drive.
const robot::OdometryAlphas kGridSlamAlphas{0.02, 0.02, 0.02, 0.02};

struct GridSlamDrive {
  robot::OccupancyGrid room = testing::laser_room(8.0, 6.0, 0.05);
  std::vector<Pose> truth, odometry;
  std::vector<LaserScan> scans;
};

// A drive through the room: east along y = 3.3 (north of the inner wall), a right turn, south
// along x = 6.1. Scans are simulated at the true poses; the odometry poses compose increments
// perturbed by kGridSlamAlphas (the semi-synthetic protocol of data/carmen/README.md).
GridSlamDrive grid_slam_drive(int steps) {
  GridSlamDrive d;
  robot::ScanSimulationOptions sim;
  sim.beams = 91;  // 2 degrees apart: the map needs no more, and each particle integrates each
  sim.range_max = 12.0;
  Pose x(1.0, 3.3, 0.0), odo = x;
  for (int k = 0; k < steps; ++k) {
    Rng rng({.seed = 17, .step = static_cast<std::uint64_t>(k), .purpose = purpose::kData});
    if (k > 0) {
      const Pose next = robot::compose(x, k < 14   ? Pose(0.3, 0.0, 0.0)
                                          : k < 21 ? Pose(0.25, 0.0, -kPi / 14)
                                                   : Pose(0.3, 0.0, 0.0));
      odo = robot::compose(odo,
                           robot::perturb_odometry(robot::between(x, next), kGridSlamAlphas, rng));
      x = next;
    }
    d.truth.push_back(x);
    d.odometry.push_back(odo);
    d.scans.push_back(robot::simulate_scan(d.room, x, {}, sim, rng));
  }
  return d;
}

GridSlamOptions grid_slam_test_options() {
  GridSlamOptions o;
  o.particles = 8;
  o.seed = 3;
  o.scan.max_beams = 30;
  o.map.max_range = 12.0;
  o.gate.linear_update = 0.1;
  o.gate.angular_update = 0.3;
  o.alphas = kGridSlamAlphas;
  return o;
}

// Mean position error of the best trajectory against the truth.
double grid_slam_filter_drive(const GridSlamDrive& d, const GridSlamOptions& o,
                              std::shared_ptr<const GridProposal> proposal,
                              std::vector<GridSlamPose>* out) {
  GridSlam filter(o, std::move(proposal));
  filter.initialize(d.truth[0], d.odometry[0], d.scans[0]);
  for (std::size_t k = 1; k < d.scans.size(); ++k) {
    const GridSlamStep r = filter.step(d.odometry[k], d.scans[k]);
    EXPECT_TRUE(r.processed) << k;
    EXPECT_EQ(r.failures, 0) << k;
  }
  const std::vector<GridSlamPose> path = filter.best_trajectory();
  EXPECT_EQ(path.size(), d.scans.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < path.size(); ++k)
    sum += (path[k].pose.head<2>() - d.truth[k].head<2>()).norm();
  if (out) *out = path;
  return sum / static_cast<double>(path.size());
}

// The scans pin each pose to about a cell (5 cm cells; the scan match smooths over 8 of them), and
// the map is built from the filter's own poses, so errors add up slowly: 2 cells on average. The
// drive must be a test of the scans: dead reckoning (the odometry's own mean error, anchored at the
// first pose) is off by more than twice that.
constexpr double kGridSlamTolerance = 0.10;

double grid_slam_recovery_error(std::shared_ptr<const GridProposal> proposal) {
  const GridSlamDrive d = grid_slam_drive(25);
  double odometry_error = 0.0;
  for (std::size_t k = 0; k < d.truth.size(); ++k)
    odometry_error += (d.odometry[k].head<2>() - d.truth[k].head<2>()).norm();
  odometry_error /= static_cast<double>(d.truth.size());
  EXPECT_GT(odometry_error, 2.0 * kGridSlamTolerance) << "the drive does not test the scans";
  const double error =
      grid_slam_filter_drive(d, grid_slam_test_options(), std::move(proposal), nullptr);
  EXPECT_LT(error, odometry_error);
  return error;
}

TEST(GridSlam, TheImplicitProposalRecoversASimulatedDrive) {
  EXPECT_LT(grid_slam_recovery_error(std::make_shared<ImplicitGridProposal>()), kGridSlamTolerance);
}

TEST(GridSlam, TheScanMatchedProposalRecoversASimulatedDrive) {
  EXPECT_LT(grid_slam_recovery_error(std::make_shared<ScanMatchGridProposal>()),
            kGridSlamTolerance);
}

// The bootstrap proposal with 8 particles only samples the odometry noise (4 cm and 2.4 degrees a
// step): it is allowed three times the tolerance (and must beat dead reckoning).
TEST(GridSlam, TheBootstrapProposalRecoversASimulatedDrive) {
  EXPECT_LT(grid_slam_recovery_error(std::make_shared<BootstrapGridProposal>()),
            3.0 * kGridSlamTolerance);
}

TEST(GridSlam, ResultsDoNotDependOnTheThreadCount) {
  const GridSlamDrive d = grid_slam_drive(8);
  const GridSlamOptions o = grid_slam_test_options();
  std::vector<GridSlamPose> one, two;
  {
    const ThreadLimit limit(1);
    grid_slam_filter_drive(d, o, std::make_shared<ImplicitGridProposal>(), &one);
  }
  {
    const ThreadLimit limit(2);
    grid_slam_filter_drive(d, o, std::make_shared<ImplicitGridProposal>(), &two);
  }
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t k = 0; k < one.size(); ++k) EXPECT_EQ(one[k].pose, two[k].pose) << k;
}

// One step of one particle on a coarse map (0.2 m cells, 4 beams): the posterior is wide enough
// for a 3-D quadrature of Z = integral N(x; f, Sigma1) p(z | x, map) dx, and the mean of the
// implicit weights (several starts; one coarse-to-fine start; the random map) and of the
// bootstrap weights must match it within 4 standard errors.
TEST(GridSlam, ImplicitWeightsAreExact) {
  const GridSlamDrive d = grid_slam_drive(2);
  robot::GridMappingOptions mo;
  mo.resolution = 0.2;
  mo.max_range = 12.0;
  TiledLogOddsGrid map(mo);
  map.integrate(d.truth[0], {}, d.scans[0]);
  ScanMatchParams sp;
  sp.max_beams = 4;
  sp.floor = 0.2;
  const GridScanModel model(map, sp);
  const ScanMatchBeams beams = model.prepare(d.scans[1]);
  ASSERT_EQ(beams.size(), 4u);
  const robot::OdometryModel motion({0.05, 0.05, 0.05, 0.05});
  const Pose previous = d.truth[0];
  const robot::OdometryDelta u = robot::between(d.truth[0], d.truth[1]) + Vec<3>(0.05, -0.03, 0.02);
  const GridProposalInput in{&motion, u, &model, &beams};
  // Z by the trapezoid rule on +-6 sd of the motion prior (spacing 0.5 sd per axis).
  Pose f;
  robot::Mat3 cov;
  motion.predict_with_covariance(previous, u, f, cov);
  const Eigen::LLT<robot::Mat3> llt(cov);
  const robot::Mat3 l = llt.matrixL();
  const int half = 12;
  const double h = 6.0 / half;
  double z = 0.0;
  for (int a = -half; a <= half; ++a)
    for (int b = -half; b <= half; ++b)
      for (int c = -half; c <= half; ++c) {
        const Vec<3> eta(a * h, b * h, c * h);
        const Pose x = f + l * eta;  // density of eta: N(0, I)
        z += std::exp(-0.5 * eta.squaredNorm() + model.log_likelihood(beams, x));
      }
  z *= std::pow(h, 3) / std::pow(2.0 * kPi, 1.5);
  for (const std::shared_ptr<const GridProposal>& proposal :
       {std::shared_ptr<const GridProposal>(std::make_shared<ImplicitGridProposal>()),
        std::shared_ptr<const GridProposal>(std::make_shared<ImplicitGridProposal>(
            ImplicitGridOptions{.coarse = {.coarse_smoothing = 4}, .starts = 1})),
        std::shared_ptr<const GridProposal>(std::make_shared<ImplicitGridProposal>(
            ImplicitGridOptions{.coarse = {}, .starts = 1, .random_map = true})),
        std::shared_ptr<const GridProposal>(std::make_shared<BootstrapGridProposal>())}) {
    const int samples = 1000;
    double sum = 0.0, sum2 = 0.0;
    for (int j = 0; j < samples; ++j) {
      Rng rng({.seed = 5, .index = static_cast<std::uint64_t>(j), .purpose = purpose::kProposal});
      Pose next;
      GridProposalStats st;
      const double w = std::exp(proposal->propose(in, previous, rng, next, st));
      EXPECT_FALSE(st.failed);
      sum += w;
      sum2 += w * w;
    }
    const double mean = sum / samples;
    const double se = std::sqrt((sum2 / samples - mean * mean) / samples);
    EXPECT_LT(se, 0.05 * z) << proposal->name() << ": too few samples to test anything";
    EXPECT_NEAR(mean, z, 4.0 * se) << proposal->name() << " Z = " << z;
  }
}

template <typename F>
std::string grid_slam_error(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(GridSlam, RefusesBadInputNamingIt) {
  const GridSlamDrive d = grid_slam_drive(2);
  const auto proposal = std::make_shared<ImplicitGridProposal>();
  const auto options_error = [&](GridSlamOptions o) {
    return grid_slam_error([&] { GridSlam filter(o, proposal); });
  };
  GridSlamOptions o;
  o.particles = 0;
  EXPECT_NE(options_error(o).find("particles"), std::string::npos);
  o = {};
  o.resample_threshold = 1.5;
  EXPECT_NE(options_error(o).find("resample_threshold"), std::string::npos);
  o = {};
  o.scan.floor = -1.0;
  EXPECT_NE(options_error(o).find("floor"), std::string::npos);
  o = {};
  o.gate.linear_update = std::nan("");
  EXPECT_NE(options_error(o).find("linear_update"), std::string::npos);
  o = {};
  o.alphas.alpha3 = -0.1;
  EXPECT_NE(options_error(o).find("alpha3"), std::string::npos);
  EXPECT_NE(grid_slam_error([&] { GridSlam filter(GridSlamOptions{}, nullptr); }).find("proposal"),
            std::string::npos);
  ScanMatchProposalOptions so;
  so.step(2) = 0.0;
  EXPECT_NE(grid_slam_error([&] { ScanMatchGridProposal p(so); }).find("step"), std::string::npos);
  so = {};
  so.coarse.coarse_smoothing = 9;
  EXPECT_NE(grid_slam_error([&] { ScanMatchGridProposal p(so); }).find("coarse_smoothing"),
            std::string::npos);
  EXPECT_NE(grid_slam_error([] {
              ImplicitGridProposal p(ImplicitGridOptions{.coarse = {}, .starts = 0});
            }).find("starts"),
            std::string::npos);

  GridSlam filter(grid_slam_test_options(), proposal);
  EXPECT_NE(grid_slam_error([&] { filter.step(d.odometry[1], d.scans[1]); }).find("initialize"),
            std::string::npos);
  filter.initialize(d.truth[0], d.odometry[0], d.scans[0]);
  const Pose nan_odometry(std::nan(""), 0.0, 0.0);
  EXPECT_NE(grid_slam_error([&] { filter.step(nan_odometry, d.scans[1]); }).find("odometry"),
            std::string::npos);
  LaserScan empty = d.scans[1];
  empty.ranges.clear();
  EXPECT_NE(grid_slam_error([&] { filter.step(d.odometry[1], empty); }).find("scan 1"),
            std::string::npos);
  EXPECT_NE(grid_slam_error([&] {
              filter.initialize(nan_odometry, d.odometry[0], d.scans[0]);
            }).find("initial pose"),
            std::string::npos);
  // Refused before any change: the filter still steps.
  EXPECT_TRUE(filter.step(d.odometry[1], d.scans[1]).processed);
  EXPECT_EQ(filter.steps(), 1u);
}

// The runner on a log made of the simulated drive's scans and true poses (as a CARMEN log's
// corrected poses): the relation errors against them, and the odometry's own, are scored.
TEST(GridSlam, RunsALogByTheSemiSyntheticProtocol) {
  const GridSlamDrive d = grid_slam_drive(25);
  robot::CarmenLog log;
  log.source = "simulated";
  log.scans = d.scans;
  log.laser_poses = d.truth;
  for (std::size_t k = 0; k < log.scans.size(); ++k) log.scans[k].time = 0.5 * k;
  GridSlamRunOptions o;
  o.filter = grid_slam_test_options();
  o.filter.alphas = {0.02, 0.02, 0.02, 0.02};
  o.filter.gate.linear_update = 0.2;  // every scan of the drive (0.25 m or more apart)
  o.proposal = parse_grid_proposal("implicit");
  const GridSlamRun run = run_grid_slam(log, o);
  EXPECT_EQ(run.processed, d.scans.size());
  ASSERT_EQ(run.trajectory.size(), run.processed);
  EXPECT_EQ(run.trajectory[3].time, 1.5);
  EXPECT_EQ(run.relations.translation.size(), run.processed - 1);
  // Dead reckoning's relation error is the odometry noise, 4 cm a step; the scans cut it (each
  // pose is still a draw from its posterior, about 2 cm wide at 5 cm cells).
  EXPECT_GT(run.odometry_relations.translation_mean, 0.03);
  EXPECT_LT(run.relations.translation_mean, 0.8 * run.odometry_relations.translation_mean);
  EXPECT_FALSE(run.map.empty());
  EXPECT_EQ(run.failures, 0u);

  EXPECT_NE(grid_slam_error([] { parse_grid_proposal("fastslam"); }).find("fastslam"),
            std::string::npos);
  EXPECT_NE(grid_slam_error([&] { run_grid_slam(robot::CarmenLog{}, o); }).find("scans"),
            std::string::npos);
  o.filter.particles = 0;
  EXPECT_NE(grid_slam_error([&] { run_grid_slam(log, o); }).find("particles"), std::string::npos);
}

}  // namespace
}  // namespace implicit::slam
