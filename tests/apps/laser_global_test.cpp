// The global start of laser MCL (experiments/laser_global.hpp): the implicit mixture (Newton from
// the best poses of a coarse search, plus a defensive uniform part) weighs exactly, so its
// estimate of Z = int p(z | x) U(x) dx agrees with the bootstrap's (uniform draws) within their
// standard errors; it puts the weight at the true pose; and the bootstrap start is the uniform one
// for any observation model (the beam model too).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/stat_helpers.hpp"
#include "experiments/laser_global.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/beam_model.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/scan_simulation.hpp"
#include "robot/laser_fixtures.hpp"

namespace implicit::experiments {
namespace {

struct Room {
  robot::OccupancyGrid grid = testing::laser_room(8.0, 6.0, 0.05);
  robot::Pose truth{2.0, 1.5, 0.4};
  robot::LaserScan scan;
  std::unique_ptr<robot::LikelihoodFieldModel> model;
  Room() {
    robot::ScanSimulationOptions o;
    o.beams = 181;
    o.range_max = 12.0;
    Rng rng({3, 0, 0, 0});
    scan = robot::simulate_scan(grid, truth, {}, o, rng);
    // Few beams and a wide sigma_hit: a posterior wide enough for the bootstrap's estimate of Z
    // to have a useful standard error with 2 10^5 uniform draws.
    robot::LikelihoodFieldParams p;
    p.max_beams = 6;
    p.sigma_hit = 0.4;
    model = std::make_unique<robot::LikelihoodFieldModel>(
        std::make_shared<const robot::DistanceField>(grid, 2.0), p);
  }
};

/// Z-hat relative to exp(offset), with its standard error, from one set of log weights.
testing::Estimate z_hat(const std::vector<double>& log_weights, double offset) {
  std::vector<double> shifted(log_weights.size());
  for (std::size_t j = 0; j < shifted.size(); ++j) shifted[j] = log_weights[j] - offset;
  return testing::normalising_constant(shifted);
}

TEST(LaserGlobalStart, TheImplicitMixtureEstimatesTheSameZAsUniformDraws) {
  const Room room;
  // The log weights of both starts are log p(z | x) + log U(x) - log q(x) up to the same
  // constant: the bootstrap's omit log U(x) - log q(x) = 0 (q = U), the mixture's include it.
  const GlobalStart boot = global_start(*room.model, room.grid, room.scan, 200000, false, 11);
  const double offset = *std::max_element(boot.log_weights.begin(), boot.log_weights.end());
  const testing::Estimate z_boot = z_hat(boot.log_weights, offset);
  // The implicit estimate: mean over 20 independent starts of M = 200 (the deterministic
  // mixture's draws are not independent within one start, so the SE comes from the repeats).
  std::vector<double> per_start;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const GlobalStart g = global_start(*room.model, room.grid, room.scan, 200, true, seed);
    per_start.push_back(z_hat(g.log_weights, offset).value);
  }
  const testing::RunSummary z_imp = testing::summarise_runs(per_start);
  const double se = std::hypot(z_boot.se, z_imp.se);
  EXPECT_LT(std::abs(z_imp.mean - z_boot.value), 4.5 * se)
      << "implicit " << z_imp.mean << " +- " << z_imp.se << ", bootstrap " << z_boot.value << " +- "
      << z_boot.se;
  // The mixture is the better importance function: a smaller standard error per draw.
  EXPECT_LT(z_imp.sd / z_imp.mean * std::sqrt(200.0),
            z_boot.se / z_boot.value * std::sqrt(200000.0));
}

TEST(LaserGlobalStart, TheImplicitStartFindsTheTruePoseAnywhereInTheMap) {
  const Room room;
  // nav2's defaults (60 beams, sigma_hit 0.2): a posterior of a few centimetres at the truth.
  const robot::LikelihoodFieldModel sharp(
      std::make_shared<const robot::DistanceField>(room.grid, 2.0), robot::LikelihoodFieldParams{});
  const GlobalStart g = global_start(sharp, room.grid, room.scan, 300, true, 5);
  // The heaviest particle is at the true pose (the scan matcher's minimum).
  const auto best = std::max_element(g.log_weights.begin(), g.log_weights.end());
  const robot::Pose& x = g.particles[static_cast<std::size_t>(best - g.log_weights.begin())];
  EXPECT_LT((x.head<2>() - room.truth.head<2>()).norm(), 0.3) << x.transpose();
  EXPECT_LT(std::abs(wrap_angle(x(2) - room.truth(2))), 0.1) << x.transpose();
}

TEST(LaserGlobalStart, TheUniformStartWorksForAnyObservationModel) {
  const Room room;
  const robot::BeamModel beam(std::make_shared<const robot::OccupancyGrid>(room.grid),
                              robot::BeamModelParams{});
  const FreeSpace space(room.grid);
  const GlobalStart g =
      uniform_global_start(beam, space, beam.prepare(room.scan, "scan"), 20000, 7);
  ASSERT_EQ(g.particles.size(), 20000u);
  for (const robot::Pose& x : g.particles) ASSERT_TRUE(space.contains(x)) << x.transpose();
  const auto best = std::max_element(g.log_weights.begin(), g.log_weights.end());
  const robot::Pose& x = g.particles[static_cast<std::size_t>(best - g.log_weights.begin())];
  // 20000 uniform draws over about 40 m^2 and 2 pi: the best lies within a few draws' spacing.
  EXPECT_LT((x.head<2>() - room.truth.head<2>()).norm(), 0.5) << x.transpose();
}

}  // namespace
}  // namespace implicit::experiments
