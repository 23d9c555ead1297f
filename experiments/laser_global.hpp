#pragma once
// A global start of laser MCL: the pose is anywhere in the map's free space, with uniform
// heading, and the first scan decides.
//
//   bootstrap: M poses drawn uniformly over the free cells, weighted by log p(z | x);
//   implicit:  the multi-start mixture. M starts drawn as above; from each, Newton minimises
//              -log p(z | x) + 1/2 |x - start|^2 / s^2 (scan matching with a weak pull towards
//              the start, s = 0.5 m and 0.5 rad) to mu_k with Hessian H_k; the sample x_k =
//              mu_k + L_k^-T xi_k of each component is weighted by
//              p(z | x_k) U(x_k) / q(x_k),  q = (1/M) sum_i N(x; mu_i, H_i^-1)
//              (the deterministic-mixture weight: unbiased with one sample per component; U is
//              the uniform prior over free space, so a sample off it weighs 0).

#include <cstdint>
#include <vector>

#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::experiments {

struct GlobalStart {
  std::vector<robot::Pose> particles;
  std::vector<double> log_weights;  ///< unnormalised
};

/// Throws InvalidArgument when the map has no free cell.
GlobalStart global_start(const robot::LikelihoodFieldModel& model, const robot::OccupancyGrid& map,
                         const robot::LaserScan& scan, std::size_t particles, bool implicit,
                         std::uint64_t seed);

}  // namespace implicit::experiments
