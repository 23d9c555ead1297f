// The beam model (robot/beam_model.hpp): per beam a proper mixed density (its integral over the
// readings plus the mass of "no return" is one, less the hit's Gaussian mass below zero), the
// scan's log-likelihood in closed form on a one-wall map, the mount, the beams it uses, and
// refusals of bad parameters.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "implicit/core/error.hpp"
#include "implicit/robot/beam_model.hpp"
#include "robot/laser_fixtures.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

std::shared_ptr<const OccupancyGrid> wall_map() {
  // 0.1 m cells; the wall is column 50, i.e. x in [5.0, 5.1).
  return std::make_shared<const OccupancyGrid>(testing::one_wall_map(120, 100, 0.1, 50));
}

/// Composite Simpson's rule of f over [a, b] with n (even) intervals.
template <typename F>
double simpson(F f, double a, double b, int n) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * f(a + i * h);
  return s * h / 3.0;
}

double standard_normal_cdf(double t) { return 0.5 * std::erfc(-t / std::sqrt(2.0)); }

TEST(BeamModel, EachBeamIsAProperDensityOverReadingsAndNoReturn) {
  BeamModelParams p;  // nav2's defaults: z_hit 0.5, z_short 0.05, z_max 0.05, z_rand 0.5
  const BeamModel model(wall_map(), p);
  const double z_max = 10.0;
  const double sum = p.z_hit + p.z_short + p.z_max + p.z_rand;
  for (double expected : {0.3, 1.0, 4.2, 9.9, 10.0}) {
    const auto density = [&](double r) {
      return std::exp(model.beam_log_density(r, false, expected, z_max));
    };
    // The density jumps at r = expected (the short component ends there): split the integral,
    // and take the piece above at its limit from the right.
    const auto right_of_jump = [&](double r) {
      return density(r == expected ? std::nextafter(expected, z_max) : r);
    };
    const double below = simpson(density, 0.0, expected, 20000);
    const double above = expected < z_max ? simpson(right_of_jump, expected, z_max, 20000) : 0.0;
    const double none = std::exp(model.beam_log_density(0.0, true, expected, z_max));
    // What is missing is the hit's Gaussian mass below zero, in closed form.
    const double missing = p.z_hit / sum * standard_normal_cdf(-expected / p.sigma_hit);
    // Simpson's error bound (b - a) h^4 max|f''''| / 180 on these smooth pieces: with h <= 5e-4
    // and the hit's |f''''| <= (z_hit / S) 3 / (sqrt(2 pi) sigma^5) ~ 1700, below 1e-11.
    EXPECT_NEAR(below + above + none, 1.0 - missing, 1e-9) << "expected range " << expected;
  }
}

TEST(BeamModel, ScanLikelihoodMatchesTheClosedFormOnOneWall) {
  BeamModelParams p;
  p.max_beams = 1000;
  const BeamModel model(wall_map(), p);
  // The robot at (2, 5) facing the wall (x = 5.0): beam b meets it at 3 / cos b.
  LaserScan scan;
  scan.angle_min = -0.5;
  scan.angle_increment = 0.1;
  scan.range_max = 8.0;
  for (int i = 0; i <= 10; ++i)
    scan.ranges.push_back(3.0 / std::cos(scan.bearing(i)) + 0.05 * (i - 5) + 0.013);
  scan.ranges[3] = std::numeric_limits<double>::infinity();  // one beam without return
  const Pose x(2.0, 5.0, 0.0);
  const PreparedBeams z = model.prepare(scan);
  ASSERT_EQ(z.size(), scan.size());
  const double sum = p.z_hit + p.z_short + p.z_max + p.z_rand, s = p.sigma_hit;
  double expected_log = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double zhat = 3.0 / std::cos(scan.bearing(i));
    const double r = scan.ranges[i];
    double q;
    if (std::isinf(r)) {
      q = p.z_hit * (1.0 - standard_normal_cdf((8.0 - zhat) / s)) + p.z_max;
    } else {
      q = p.z_hit * std::exp(-0.5 * (r - zhat) * (r - zhat) / (s * s)) / (std::sqrt(2 * kPi) * s) +
          p.z_rand / 8.0;
      if (r <= zhat)
        q += p.z_short * p.lambda_short * std::exp(-p.lambda_short * r) /
             (1.0 - std::exp(-p.lambda_short * zhat));
    }
    expected_log += std::log(q / sum);
  }
  EXPECT_NEAR(model.log_likelihood(z, x), expected_log, 1e-9 * std::abs(expected_log));
}

TEST(BeamModel, ANoReturnBeamSaysTheWayWasFree) {
  const BeamModel model(wall_map(), BeamModelParams{});
  LaserScan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 0.1;
  scan.range_max = 8.0;
  scan.ranges = {std::numeric_limits<double>::infinity()};
  const PreparedBeams z = model.prepare(scan);
  // Facing the wall 1 m away it should have returned; facing away (8 m of free space) not.
  EXPECT_LT(model.log_likelihood(z, Pose(4.0, 5.0, 0.0)),
            model.log_likelihood(z, Pose(4.0, 5.0, kPi)) - 1.0);
}

TEST(BeamModel, TheMountMovesTheBeamsOrigin) {
  LaserMount mount{0.5, 0.2, 0.3};
  const BeamModel mounted(wall_map(), BeamModelParams{}, mount);
  const BeamModel bare(wall_map(), BeamModelParams{});
  LaserScan scan;
  scan.angle_min = -0.4;
  scan.angle_increment = 0.2;
  scan.range_max = 8.0;
  scan.ranges = {3.1, 2.9, 3.0, 3.3, 4.0};
  const Pose x(1.5, 4.0, 0.2);
  // The mounted laser at x sees what a bare laser sees at x ⊕ mount.
  const Pose sensor = compose(x, Pose(mount.x, mount.y, mount.yaw));
  EXPECT_NEAR(mounted.log_likelihood(mounted.prepare(scan), x),
              bare.log_likelihood(bare.prepare(scan), sensor), 1e-9);
}

TEST(BeamModel, UsesMaxBeamsEvenlySpacedAndSkipsShortReadings) {
  BeamModelParams p;
  p.max_beams = 3;
  const BeamModel model(wall_map(), p);
  LaserScan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 0.1;
  scan.range_min = 0.1;
  scan.range_max = 8.0;
  scan.ranges = {1.0, 2.0, 3.0, 4.0, 0.05};
  const PreparedBeams z = model.prepare(scan);
  ASSERT_EQ(z.size(), 2u);  // beams 0, 2 and 4; beam 4 is below range_min
  EXPECT_EQ(z.skipped_short, 1u);
  EXPECT_DOUBLE_EQ(z.beams[1].range, 3.0);
  EXPECT_DOUBLE_EQ(z.beams[1].bearing, 0.2);
  EXPECT_FALSE(model.differentiable());
  EXPECT_THAT(std::string(model.why_not_differentiable()), HasSubstr("likelihood field"));
}

TEST(BeamModel, RefusesBadParametersAndScans) {
  const auto refuses = [](BeamModelParams p, const char* what) {
    try {
      BeamModel model(wall_map(), p);
      ADD_FAILURE() << "accepted " << what;
    } catch (const InvalidArgument& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  BeamModelParams p;
  p.z_hit = 0.0;
  refuses(p, "z_hit");
  p = {};
  p.z_short = -1.0;
  refuses(p, "z_short");
  p = {};
  p.z_max = std::nan("");
  refuses(p, "z_max");
  p = {};
  p.sigma_hit = 0.0;
  refuses(p, "sigma_hit");
  p = {};
  p.lambda_short = -0.1;
  refuses(p, "lambda_short");
  p = {};
  p.max_beams = 0;
  refuses(p, "max_beams");
  EXPECT_THROW(BeamModel(nullptr, BeamModelParams{}), InvalidArgument);
  const BeamModel model(wall_map(), BeamModelParams{});
  LaserScan scan;
  scan.angle_increment = 0.1;
  scan.range_max = 8.0;
  scan.ranges = {1.0, std::nan("")};
  try {
    (void)model.prepare(scan, "log.txt:7");
    ADD_FAILURE() << "accepted a NaN range";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("log.txt:7"));
  }
  // A diverged particle weighs nothing; it does not throw.
  scan.ranges = {1.0, 2.0};
  EXPECT_EQ(model.log_likelihood(model.prepare(scan), Pose(std::nan(""), 0.0, 0.0)),
            -std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace implicit::robot
