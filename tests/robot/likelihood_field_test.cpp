// The likelihood-field laser model: the closed form on a one-wall map, its derivatives against
// finite differences, beam selection as nav2 does it, and the refusals.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Eigenvalues>

#include "implicit/core/rng.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "robot/laser_fixtures.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

constexpr double kRes = 0.1;

/// A scan of n beams, all reading r, over [-pi/2, pi/2].
LaserScan fan(int n, double r, double range_max = 20.0) {
  LaserScan s;
  s.angle_min = -kPi / 2;
  s.angle_increment = n > 1 ? kPi / (n - 1) : 0.1;
  s.range_min = 0.05;
  s.range_max = range_max;
  s.ranges.assign(static_cast<std::size_t>(n), r);
  return s;
}

double beam_density_by_hand(const LikelihoodFieldParams& p, double d, double z_max) {
  const double s = p.sigma_hit;
  return p.z_hit * std::exp(-0.5 * d * d / (s * s)) / (std::sqrt(2 * kPi) * s) + p.z_rand / z_max;
}

std::shared_ptr<const DistanceField> wall_field(double max_distance = 2.0) {
  // 60 x 40 cells of 0.1 m; the wall is column 30, centre x = 3.05.
  return std::make_shared<const DistanceField>(testing::one_wall_map(60, 40, kRes, 30),
                                               max_distance);
}

TEST(LikelihoodField, OneWallMapMatchesTheClosedFormAtCellCentres) {
  LikelihoodFieldParams p;
  p.max_beams = 1000;
  for (Interpolation mode :
       {Interpolation::kNearest, Interpolation::kBilinear, Interpolation::kBicubic}) {
    p.interpolation = mode;
    LikelihoodFieldModel model(wall_field(), p);
    // Robot at the centre of cell (10, 20), heading 0: a beam straight ahead of length k * 0.1
    // ends on a cell centre at distance (20 - k) * 0.1 from the wall's centre line.
    LaserScan s;
    s.angle_min = 0.0;
    s.angle_increment = 0.1;
    s.range_min = 0.05;
    s.range_max = 20.0;
    s.ranges = {0.5};  // one beam, 0.5 m ahead: ends at x = 1.55, 1.5 m from the wall
    const PreparedScan z = model.prepare(s);
    ASSERT_EQ(z.size(), 1u);
    const Pose x(1.05, 2.05, 0.0);
    const double expected = std::log(beam_density_by_hand(p, 1.5, 20.0));
    EXPECT_NEAR(model.log_likelihood(z, x), expected, 1e-6) << static_cast<int>(mode);
  }
}

TEST(LikelihoodField, NearestCellIsTheCellValueAnywhereInTheCell) {
  LikelihoodFieldParams p;
  p.interpolation = Interpolation::kNearest;
  p.max_beams = 1000;
  LikelihoodFieldModel model(wall_field(), p);
  LaserScan s = fan(3, 1.0);
  const PreparedScan z = model.prepare(s);
  Rng rng({7, 0, 0, 0});
  for (int k = 0; k < 50; ++k) {
    const double uh = rng.uniform(), uy = rng.uniform(), ux = rng.uniform();  // in this order
    const Pose x(0.5 + 2.0 * ux, 0.8 + 2.0 * uy, uh - 0.5);
    const double c = std::cos(x(2)), sn = std::sin(x(2));
    double expected = 0.0;
    for (const Vec<2>& e : z.end_points) {
      const double px = x(0) + c * e(0) - sn * e(1);
      const int ix = static_cast<int>(std::floor(px / kRes));
      const double centre = (ix + 0.5) * kRes;
      const double d = std::min(std::abs(centre - 3.05), 2.0);
      expected += std::log(beam_density_by_hand(p, d, 20.0));
    }
    EXPECT_NEAR(model.log_likelihood(z, x), expected, 1e-5);
  }
}

TEST(LikelihoodField, NegativeLogLikelihoodIsMinusTheLogLikelihood) {
  LikelihoodFieldParams p;
  LikelihoodFieldModel model(wall_field(), p);
  const PreparedScan z = model.prepare(fan(30, 1.7));
  const Pose x(1.3, 2.1, 0.2);
  EXPECT_NEAR(model.negative_log_likelihood(z, x, nullptr, nullptr), -model.log_likelihood(z, x),
              1e-9);
}

TEST(LikelihoodField, GradientMatchesCentralDifferencesAndGaussNewtonIsPsd) {
  LikelihoodFieldParams p;
  p.interpolation = Interpolation::kBicubic;
  p.max_beams = 40;
  auto room = std::make_shared<const DistanceField>(testing::laser_room(8.0, 6.0, 0.05), 2.0);
  LikelihoodFieldModel model(room, p, LaserMount{0.2, 0.05, 0.1});
  LaserScan s = fan(90, 2.3);
  for (std::size_t i = 0; i < s.ranges.size(); ++i)
    s.ranges[i] = 0.8 + 0.03 * static_cast<double>(i);
  const PreparedScan z = model.prepare(s);
  Rng rng({11, 0, 0, 0});
  for (int k = 0; k < 40; ++k) {
    const double ux = rng.uniform(), uy = rng.uniform(), uh = rng.uniform();  // in this order
    const Pose x(1.0 + 5.5 * ux, 1.0 + 3.8 * uy, 2 * kPi * uh);
    Vec<3> g = Vec<3>::Zero();
    Mat3 h = Mat3::Zero();
    model.negative_log_likelihood(z, x, &g, &h);
    for (int a = 0; a < 3; ++a) {
      const double step = 1e-6;
      Pose xp = x, xm = x;
      xp(a) += step;
      xm(a) -= step;
      const double fd = (model.negative_log_likelihood(z, xp, nullptr, nullptr) -
                         model.negative_log_likelihood(z, xm, nullptr, nullptr)) /
                        (2 * step);
      EXPECT_NEAR(g(a), fd, 1e-4 * (1.0 + std::abs(fd)))
          << "component " << a << " at " << x.transpose();
    }
    EXPECT_LT((h - h.transpose()).norm(), 1e-12);
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(h);
    EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-9 * (1.0 + eig.eigenvalues().maxCoeff()));
  }
}

/// log p as the sum over beams of beam_log_density at the capped field distance of each end
/// point: the model's definition, beam by beam, without its table or its product of densities.
double sum_of_beam_densities(const LikelihoodFieldModel& model, const PreparedScan& z,
                             const Pose& x, double* largest_term) {
  const double c = std::cos(x(2)), s = std::sin(x(2));
  const double cap =
      std::min(model.params().laser_likelihood_max_dist, model.field().max_distance());
  double total = 0.0;
  *largest_term = 1.0;
  for (const Vec<2>& e : z.end_points) {
    const Vec<2> p(x(0) + c * e(0) - s * e(1), x(1) + s * e(0) + c * e(1));
    const double d = std::min(model.field().distance(p, model.params().interpolation), cap);
    const double term = model.beam_log_density(z, d);
    *largest_term = std::max(*largest_term, std::abs(term));
    total += term;
  }
  return total;
}

TEST(LikelihoodField, EqualsTheSumOfBeamDensitiesForEveryModeAndDensityForm) {
  auto room = std::make_shared<const DistanceField>(testing::laser_room(8.0, 6.0, 0.05), 2.0);
  LaserScan s = fan(400, 1.0);
  for (std::size_t i = 0; i < s.ranges.size(); ++i)
    s.ranges[i] = 0.5 + 4.0 * std::abs(std::sin(0.05 * static_cast<double>(i)));
  // The default density; no uniform term (the log of e^h kept exact where e^h underflows:
  // sigma 1 cm gives h = -20000 at the cap); a uniform term too small for the product of
  // densities to stay a normal number (the logs are summed instead).
  LikelihoodFieldParams base;
  base.max_beams = 300;  // renormalises the product many times
  LikelihoodFieldParams no_uniform = base;
  no_uniform.z_rand = 0.0;
  no_uniform.sigma_hit = 0.01;
  LikelihoodFieldParams tiny_uniform = base;
  tiny_uniform.z_rand = 1e-300;
  Rng rng({5, 0, 0, 0});
  for (const LikelihoodFieldParams& density : {base, no_uniform, tiny_uniform}) {
    for (Interpolation mode :
         {Interpolation::kNearest, Interpolation::kBilinear, Interpolation::kBicubic}) {
      LikelihoodFieldParams p = density;
      p.interpolation = mode;
      const LikelihoodFieldModel model(room, p);
      const PreparedScan z = model.prepare(s);
      ASSERT_EQ(z.size(), 300u);
      for (int k = 0; k < 30; ++k) {
        // Inside the room, and (k >= 25) around and far outside the map.
        const double spread = k < 25 ? 1.0 : 40.0;
        const double ux = rng.uniform(), uy = rng.uniform(), uh = rng.uniform();  // in order
        const Pose x(4.0 + spread * 3.5 * (2 * ux - 1), 3.0 + spread * 2.5 * (2 * uy - 1),
                     2 * kPi * uh);
        double largest = 0.0;
        const double expected = sum_of_beam_densities(model, z, x, &largest);
        // Rounding: the nearest table holds each beam's density as a float (2^-24 relative);
        // otherwise a few double roundings per beam, in the sum or in the product of densities.
        const double per_beam =
            mode == Interpolation::kNearest ? std::ldexp(1.0, -24) : 8 * std::ldexp(1.0, -52);
        const double tolerance = per_beam * static_cast<double>(z.size()) * largest;
        EXPECT_NEAR(model.log_likelihood(z, x), expected, tolerance)
            << "mode " << static_cast<int>(mode) << ", z_rand " << p.z_rand << ", at "
            << x.transpose();
        if (mode != Interpolation::kNearest) {
          EXPECT_NEAR(model.negative_log_likelihood(z, x, nullptr, nullptr), -expected, tolerance);
        }
      }
      EXPECT_TRUE(std::isnan(model.log_likelihood(z, Pose(1.0, std::nan(""), 0.0))));
      EXPECT_TRUE(std::isnan(model.log_likelihood(z, Pose(1.0, 1.0, std::nan("")))));
    }
  }
}

TEST(LikelihoodField, AScanPreparedByAnotherModelUsesItsConstantsNotItsTable) {
  // Model a tabulates its beam density over the room; model b reads another map. A scan
  // prepared by a must not be looked up in a's table with b's cells.
  LikelihoodFieldParams p;
  p.interpolation = Interpolation::kNearest;
  p.max_beams = 50;
  const LikelihoodFieldModel a(
      std::make_shared<const DistanceField>(testing::laser_room(8.0, 6.0, 0.05), 2.0), p);
  const LikelihoodFieldModel b(wall_field(), p);
  const PreparedScan z = a.prepare(fan(50, 1.2));
  ASSERT_NE(z.cell_log_density, nullptr);
  const Pose x(1.3, 2.2, 0.4);
  double largest = 0.0;
  const double expected = sum_of_beam_densities(b, z, x, &largest);
  EXPECT_NEAR(b.log_likelihood(z, x), expected, 8 * std::ldexp(1.0, -52) * 50 * largest);
  // A copy of a shares its table.
  const LikelihoodFieldModel copy = a;
  EXPECT_EQ(copy.prepare(fan(50, 1.2)).cell_log_density, z.cell_log_density);
}

TEST(LikelihoodField, SkipsNoReturnAndShortReadingsAndSubsamplesLikeNav2) {
  LikelihoodFieldParams p;
  p.max_beams = 5;
  LikelihoodFieldModel model(wall_field(), p);
  LaserScan s = fan(9, 1.0, 20.0);
  // Beams used: 0, 2, 4, 6, 8 (step (9 - 1) / (5 - 1) = 2).
  s.ranges[2] = 20.0;                                     // at range_max: no return
  s.ranges[4] = std::numeric_limits<double>::infinity();  // no return
  s.ranges[6] = 0.01;                                     // below range_min
  s.ranges[1] = 0.01;                                     // not selected
  const PreparedScan z = model.prepare(s);
  EXPECT_EQ(z.size(), 2u);
  EXPECT_EQ(z.skipped_no_return, 2u);
  EXPECT_EQ(z.skipped_short, 1u);
  // Beam 0 at bearing -pi/2: end point (0, -1) in the robot frame.
  EXPECT_NEAR(z.end_points[0](0), 0.0, 1e-12);
  EXPECT_NEAR(z.end_points[0](1), -1.0, 1e-12);
  // laser_max_range below the scan's: readings at or above it count as no return.
  p.laser_max_range = 0.9;
  LikelihoodFieldModel shorter(wall_field(), p);
  EXPECT_EQ(shorter.prepare(fan(9, 1.0)).size(), 0u);
}

TEST(LikelihoodField, CubedSumIsNav2sAggregationAndNotDifferentiable) {
  LikelihoodFieldParams p;
  p.aggregation = BeamAggregation::kCubedSum;
  p.interpolation = Interpolation::kNearest;
  p.max_beams = 1000;
  LikelihoodFieldModel model(wall_field(), p);
  LaserScan s;
  s.angle_min = 0.0;
  s.angle_increment = 0.1;
  s.range_min = 0.05;
  s.range_max = 20.0;
  s.ranges = {0.5};
  const PreparedScan z = model.prepare(s);
  const double pz =
      p.z_hit * std::exp(-0.5 * 1.5 * 1.5 / (p.sigma_hit * p.sigma_hit)) + p.z_rand / 20.0;
  EXPECT_NEAR(model.log_likelihood(z, Pose(1.05, 2.05, 0.0)), std::log(1.0 + pz * pz * pz), 1e-9);
  EXPECT_FALSE(model.differentiable());
  EXPECT_THAT(std::string(model.why_not_differentiable()), HasSubstr("not a likelihood"));
}

TEST(LikelihoodField, RefusesBadParametersAndScans) {
  auto field = wall_field();
  auto refused = [&](LikelihoodFieldParams p, const char* what) {
    try {
      LikelihoodFieldModel m(field, p);
      ADD_FAILURE() << "accepted " << what;
    } catch (const InvalidArgument& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  LikelihoodFieldParams p;
  p.sigma_hit = 0.0;
  refused(p, "sigma_hit");
  p = {};
  p.z_hit = std::nan("");
  refused(p, "z_hit");
  p = {};
  p.z_rand = -0.1;
  refused(p, "z_rand");
  p = {};
  p.max_beams = 0;
  refused(p, "max_beams");
  p = {};
  p.laser_likelihood_max_dist = -1;
  refused(p, "laser_likelihood_max_dist");
  EXPECT_THROW(LikelihoodFieldModel(nullptr, LikelihoodFieldParams{}), InvalidArgument);

  LikelihoodFieldModel model(field, LikelihoodFieldParams{});
  LaserScan nan_scan = fan(5, 1.0);
  nan_scan.ranges[3] = std::nan("");
  try {
    model.prepare(nan_scan, "test.log line 7");
    ADD_FAILURE() << "accepted a NaN range";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("test.log line 7"));
    EXPECT_THAT(e.what(), HasSubstr("beam 3"));
  }
  LaserScan empty = fan(5, 1.0);
  empty.ranges.clear();
  EXPECT_THROW(model.prepare(empty), InvalidArgument);
}

}  // namespace
}  // namespace implicit::robot
