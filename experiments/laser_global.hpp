#pragma once
// A global start of laser MCL: the pose is anywhere in the map's free space, with uniform
// heading, and the first scan decides.
//
//   bootstrap: M poses drawn uniformly over the free cells, weighted by log p(z | x);
//   implicit:  the multi-start mixture. 9M/10 starts: the best poses of an exhaustive search of
//              log p(z | x) over a coarse grid of free space (0.25 m, 10 degrees); M/10 poses
//              drawn uniformly as above (a defensive component). From each start, Newton minimises
//              -log p(z | x) + 1/2 |x - start|^2 / s^2 (scan matching with a weak pull towards
//              the start, s = 0.5 m and 0.5 rad) to mu_k with Hessian H_k; the sample x_k =
//              mu_k + L_k^-T xi_k of each component is weighted by
//              p(z | x_k) U(x_k) / q(x_k),  q = (1/n) [sum_i N(x; mu_i, H_i^-1) + u U(x)]
//              (the deterministic-mixture weight over the n usable draws, u of them uniform:
//              unbiased with one sample per component; U is the uniform prior over free space,
//              so a sample off it weighs 0). The starts depend on the scan, not on the draws,
//              so the weights stay exact.

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/recovery.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::experiments {

struct GlobalStart {
  std::vector<robot::Pose> particles;
  std::vector<double> log_weights;  ///< unnormalised
};

/// The free cells of a map: where a robot may be, drawn from uniformly (position uniform in a
/// uniformly chosen free cell, heading uniform).
class FreeSpace {
 public:
  /// Throws InvalidArgument when the map has no free cell.
  explicit FreeSpace(const robot::OccupancyGrid& map);
  robot::Pose draw(Rng& rng) const;
  bool contains(const robot::Pose& x) const;
  /// log of the uniform density over free space and headings: -log(area * 2 pi).
  double log_density() const;
  const robot::OccupancyGrid& map() const { return *map_; }
  const std::vector<Eigen::Vector2i>& cells() const { return cells_; }

 private:
  const robot::OccupancyGrid* map_;
  std::vector<Eigen::Vector2i> cells_;
};

/// The bootstrap global start on any observation model: M poses drawn uniformly over free space,
/// weighted by log p(z | x).
template <typename Model>
GlobalStart uniform_global_start(const Model& model, const FreeSpace& space,
                                 const typename Model::Prepared& z, std::size_t particles,
                                 std::uint64_t seed) {
  GlobalStart g;
  g.particles.resize(particles);
  g.log_weights.resize(particles);
  parallel_for(particles, [&](std::size_t j) {
    Rng rng({seed, 0, j, purpose::kGlobalInit});
    g.particles[j] = space.draw(rng);
    g.log_weights[j] = model.log_likelihood(z, g.particles[j]);
  });
  return g;
}

/// Scan matching near `start`: Newton from it on -log p(z | x) + |x - start|^2 / (2 s^2), the
/// weak pull s = 0.5 m and 0.5 rad keeping it in the start's neighbourhood (a corridor's
/// direction or a featureless wall leave -log p(z | x) flat). The global start's components and
/// a global run's first-scan fit (laser_mcl.hpp) use it. `model` must be differentiable().
NewtonMinimum<SmallFactor<3>> match_scan_near(const robot::LikelihoodFieldModel& model,
                                              const robot::PreparedScan& z,
                                              const robot::Pose& start);

/// A global start on the likelihood field: uniform for the bootstrap proposal (or a model
/// without derivatives), the multi-start mixture for the implicit one. Throws InvalidArgument
/// when the map has no free cell.
GlobalStart global_start(const robot::LikelihoodFieldModel& model, const robot::OccupancyGrid& map,
                         const robot::LaserScan& scan, std::size_t particles, bool implicit,
                         std::uint64_t seed);

/// Recovery's source for a laser filter (filter/recovery.hpp): AMCL's, poses drawn uniformly over
/// free space. The robot is assumed kidnapped to a uniform pose, so log u(x) - log g(x) = 0 and
/// an injected particle weighs p(z | x).
template <typename Context>
class UniformRecovery final : public filter::RecoverySource<Context> {
 public:
  explicit UniformRecovery(std::shared_ptr<const FreeSpace> space) : space_(std::move(space)) {}
  bool prepare(const Context& ctx) override { return ctx.z != nullptr; }
  double draw(const Context& ctx, Rng& rng, robot::Pose& x) const override {
    x = space_->draw(rng);
    return ctx.observation->log_likelihood(*ctx.z, x);
  }

 private:
  std::shared_ptr<const FreeSpace> space_;
};

}  // namespace implicit::experiments
