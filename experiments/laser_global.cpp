#include "experiments/laser_global.hpp"

#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/pose_objective.hpp"

namespace implicit::experiments {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

/// One component of the mixture: its centre and the factor of its Hessian.
struct Component {
  robot::Pose mu = robot::Pose::Zero();
  SmallFactor<3> factor;
  bool ok = false;
};

double log_normal(const Component& c, const robot::Pose& x) {
  Vec<3> d = x - c.mu;
  d(2) = wrap_angle(d(2));
  // |L^T d|^2 with H = L L^T.
  const Vec<3> v = c.factor.matrixL().transpose() * d;
  return -1.5 * kLog2Pi + c.factor.log_det_L() - 0.5 * v.squaredNorm();
}

}  // namespace

FreeSpace::FreeSpace(const robot::OccupancyGrid& map) : map_(&map) {
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix)
      if (map.is_free(ix, iy)) cells_.emplace_back(ix, iy);
  require(!cells_.empty(), "global start: the map has no free cell to start in");
}

robot::Pose FreeSpace::draw(Rng& rng) const {
  const auto k = static_cast<std::size_t>(rng.uniform() * static_cast<double>(cells_.size()));
  const Eigen::Vector2i c = cells_[std::min(k, cells_.size() - 1)];
  const double h = map_->resolution();
  const Vec<2> corner = map_->origin() + h * c.cast<double>();
  const double ux = rng.uniform(), uy = rng.uniform(), uh = rng.uniform();  // in this order
  const Vec<3> u(ux, uy, uh);
  return robot::Pose(corner(0) + h * u(0), corner(1) + h * u(1), kPi * (2.0 * u(2) - 1.0));
}

bool FreeSpace::contains(const robot::Pose& x) const {
  const Eigen::Vector2i c = map_->cell_of(x.head<2>());
  return map_->contains(c(0), c(1)) && map_->is_free(c(0), c(1));
}

GlobalStart global_start(const robot::LikelihoodFieldModel& model, const robot::OccupancyGrid& map,
                         const robot::LaserScan& scan, std::size_t particles, bool implicit,
                         std::uint64_t seed) {
  require(particles >= 1, "global start: expected at least one particle");
  const FreeSpace space(map);
  const robot::PreparedScan z = model.prepare(scan, "the global start's scan");
  if (!implicit || !model.differentiable())
    return uniform_global_start(model, space, z, particles, seed);
  GlobalStart g;
  g.particles.resize(particles);
  g.log_weights.assign(particles, kNegInf);
  const double s = 0.5;
  const robot::Mat3 pull = robot::Mat3::Identity() / (s * s);
  std::vector<Component> comps(particles);
  parallel_for(particles, [&](std::size_t k) {
    Rng rng({seed, 0, k, purpose::kGlobalInit});
    const robot::Pose start = space.draw(rng);
    filter::PoseObjective<robot::LikelihoodFieldModel> f;
    f.reset(model, z, start, pull, 0.0);
    const auto r = newton_minimize<SmallFactor<3>>(f, start, filter::scan_newton_options());
    Component& c = comps[k];
    c.ok = r.factor_ok && std::isfinite(r.value) && r.x.allFinite();
    if (c.ok) {
      c.mu = r.x;
      c.factor = r.factor;
    }
    // The component's own sample (one per component: the deterministic mixture).
    const Vec<3> xi = rng.normal_vector<3>();
    if (!c.ok) {
      g.particles[k] = start;
      return;
    }
    Vec<3> offset = xi;
    c.factor.upper_solve_in_place(offset);
    g.particles[k] = c.mu + offset;
    g.particles[k](2) = wrap_angle(g.particles[k](2));
  });
  std::size_t usable = 0;
  for (const Component& c : comps) usable += c.ok ? 1 : 0;
  require(usable > 0, "global start: no start of the scan matching gave a usable minimum");
  const double log_k = std::log(static_cast<double>(usable));
  parallel_for(
      particles,
      [&](std::size_t j) {
        if (!comps[j].ok || !space.contains(g.particles[j])) return;
        // log sum_i N_i(x_j), accumulated with a running maximum (no allocation per particle).
        double top = kNegInf, sum = 0.0;
        for (const Component& c : comps) {
          if (!c.ok) continue;
          const double l = log_normal(c, g.particles[j]);
          if (l > top) {
            sum = sum * std::exp(top - l) + 1.0;
            top = l;
          } else {
            sum += std::exp(l - top);
          }
        }
        const double log_q = top + std::log(sum) - log_k;
        g.log_weights[j] = model.log_likelihood(z, g.particles[j]) - log_q;
      },
      4);
  return g;
}

}  // namespace implicit::experiments
