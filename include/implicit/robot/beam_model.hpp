#pragma once
// The beam model of a laser (Thrun, Burgard & Fox, Probabilistic Robotics §6.3), as one
// observation model per scan (observation_model.hpp), with nav2 AMCL's parameter names.
//
// Each used beam i leaves the laser at robot pose x along heading x_theta + b_i (b_i: the beam's
// bearing on the robot, mount yaw included); the map decides where it should end: the expected
// range zhat_i(x) is the ray cast through the occupancy grid to the first occupied cell, capped
// at the maximum range z_max (occupancy_grid.hpp, cast_ray). A reading r_i < z_max has density
//
//   p(r | zhat) = [ z_hit N(r; zhat, sigma_hit^2)                                    a hit
//                 + z_short lambda e^(-lambda r) / (1 - e^(-lambda zhat)) [r <= zhat] a person in
//                 the way
//                 + z_rand / z_max ] / S                                             anything
//
// and a reading without return (r >= z_max) has probability
//
//   P(no return | zhat) = [ z_hit Q((z_max - zhat) / sigma_hit) + z_max ] / S,
//
// Q the standard normal's upper tail: a hit whose Gaussian reading would lie beyond the range
// is seen as no return (a censored reading), and z_max is the chance of a missed echo. S = z_hit
// + z_short + z_max + z_rand normalises the weights, so per beam the density on [0, z_max) and
// the point mass of "no return" add up to one, less the hit's Gaussian mass below 0 (Phi(-zhat /
// sigma_hit): nothing unless a wall is within a few sigma_hit of the laser). log p(scan | x) is
// the sum over the used beams; unlike the likelihood field, readings without return count: they
// say the beam's way was free.
//
// nav2's beam model sums p^3 instead (not a likelihood) and does not normalise; this is the
// likelihood. The expected range is a step function of the pose at cell boundaries, so the model
// has no derivatives: the bootstrap proposal, global starts and recovery use it; the implicit
// proposal refuses it and names the likelihood field instead.
//
//   auto map = std::make_shared<const OccupancyGrid>(load_map("map.yaml"));
//   BeamModel model(map, BeamModelParams{}, LaserMount{});
//   BeamModel::Prepared beams = model.prepare(scan);   // once per scan
//   double log_p = model.log_likelihood(beams, pose);  // per particle: one ray cast per beam

#include <cstddef>
#include <memory>
#include <string_view>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

/// nav2 AMCL's names and defaults for the beam model.
struct BeamModelParams {
  double z_hit = 0.5;
  double z_short = 0.05;
  double z_max = 0.05;
  double z_rand = 0.5;
  double sigma_hit = 0.2;     ///< [m]
  double lambda_short = 0.1;  ///< [1/m]
  int max_beams = 60;
  double laser_max_range = -1.0;  ///< [m]; <= 0: the scan's range_max
  double laser_min_range = -1.0;  ///< [m]; <= 0: the scan's range_min

  /// Throws InvalidArgument naming the parameter.
  void validate() const;
};

/// One scan's used beams and the constants of their density: computed once per scan.
struct PreparedBeams {
  struct Beam {
    double range = 0.0;    ///< [m] the reading (z_max for a reading without return)
    double bearing = 0.0;  ///< [rad] on the robot: the mount's yaw plus the beam's bearing
    bool no_return = false;
  };
  std::vector<Beam> beams;
  double z_max = 0.0;             ///< the maximum range this scan was read with [m]
  std::size_t skipped_short = 0;  ///< readings below the minimum range
  std::size_t size() const { return beams.size(); }
};

class BeamModel {
 public:
  using Observation = LaserScan;
  using Prepared = PreparedBeams;

  /// Throws InvalidArgument for a null or empty map, or invalid parameters.
  BeamModel(std::shared_ptr<const OccupancyGrid> map, const BeamModelParams& p,
            const LaserMount& mount = {});

  const BeamModelParams& params() const { return p_; }
  const LaserMount& mount() const { return mount_; }
  const OccupancyGrid& map() const { return *map_; }

  /// The model has no derivatives (the expected range is a step function of the pose).
  bool differentiable() const { return false; }
  std::string_view why_not_differentiable() const;

  /// The beams this model uses of `scan` (validated; `where` names it in errors).
  PreparedBeams prepare(const LaserScan& scan, std::string_view where = "laser scan") const;

  /// log p(scan | x): one ray cast per used beam.
  double log_likelihood(const PreparedBeams& z, const Pose& x) const;

  /// The log density of one beam: reading `range` (ignored when no_return) where the map puts
  /// the wall at `expected` (<= z_max), for a scan read with maximum range z_max.
  double beam_log_density(double range, bool no_return, double expected, double z_max) const;

 private:
  std::shared_ptr<const OccupancyGrid> map_;
  BeamModelParams p_;
  LaserMount mount_;
  double log_sum_ = 0.0;  ///< log S, S = z_hit + z_short + z_max + z_rand
};

}  // namespace implicit::robot
