#include "experiments/laser_global.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
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
  return gaussian_log_density(3, -c.factor.log_det_L(), v.squaredNorm());
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

double FreeSpace::log_density() const {
  const double h = map_->resolution();
  return -std::log(static_cast<double>(cells_.size()) * h * h * 2.0 * kPi);
}

bool FreeSpace::contains(const robot::Pose& x) const {
  const Eigen::Vector2i c = map_->cell_of(x.head<2>());
  return map_->contains(c(0), c(1)) && map_->is_free(c(0), c(1));
}

namespace {

/// Newton's starts for the mixture: the k best poses, by log p(z | x), of an exhaustive search
/// over a coarse grid of free space (every `stride` cells, kCoarseHeadings headings). Uniform
/// starts would find the basin of the right pose only by luck in a large map (about a basin of
/// 0.5 m and 0.3 rad among hundreds of square metres); the search finds it whenever a coarse
/// pose near it explains the scan better than most of the map. Ties go to the lower index, so
/// the choice does not depend on the thread count.
constexpr int kCoarseHeadings = 36;
constexpr double kCoarseSpacing = 0.25;  ///< [m]

std::vector<robot::Pose> best_coarse_poses(const robot::LikelihoodFieldModel& model,
                                           const robot::PreparedScan& z, const FreeSpace& space,
                                           std::size_t k) {
  const robot::OccupancyGrid& map = space.map();
  const int stride = std::max(1, static_cast<int>(std::lround(kCoarseSpacing / map.resolution())));
  const int gw = map.width() / stride + 1, gh = map.height() / stride + 1;
  struct Candidate {
    int gx, gy, h;
  };
  std::vector<Candidate> grid;
  for (const Eigen::Vector2i& c : space.cells())
    if (c(0) % stride == 0 && c(1) % stride == 0)
      for (int h = 0; h < kCoarseHeadings; ++h) grid.push_back({c(0) / stride, c(1) / stride, h});
  const auto pose_of = [&](const Candidate& c) {
    const Vec<2> p = map.cell_center(c.gx * stride, c.gy * stride);
    return robot::Pose(p(0), p(1), -kPi + 2.0 * kPi * c.h / kCoarseHeadings);
  };
  std::vector<double> score(grid.size());
  parallel_for(
      grid.size(), [&](std::size_t i) { score[i] = model.log_likelihood(z, pose_of(grid[i])); },
      256);
  std::vector<std::size_t> order(grid.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return score[a] > score[b] || (score[a] == score[b] && a < b);
  });
  // Non-maximum suppression: a kept pose claims its neighbours (one step in x, y and heading),
  // whose Newton runs would end in the same minimum; so the starts cover k distinct places
  // instead of crowding around the few best, and an ambiguous scan keeps all its candidates.
  std::vector<char> claimed(static_cast<std::size_t>(gw) * gh * kCoarseHeadings, 0);
  const auto at = [&](int x, int y, int h) {
    return (static_cast<std::size_t>(y) * gw + x) * kCoarseHeadings +
           static_cast<std::size_t>((h + kCoarseHeadings) % kCoarseHeadings);
  };
  std::vector<robot::Pose> best;
  for (std::size_t i : order) {
    if (best.size() == k) break;
    const Candidate& c = grid[i];
    if (claimed[at(c.gx, c.gy, c.h)]) continue;
    best.push_back(pose_of(c));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        for (int dh = -1; dh <= 1; ++dh) {
          const int x = c.gx + dx, y = c.gy + dy;
          if (x >= 0 && y >= 0 && x < gw && y < gh) claimed[at(x, y, c.h + dh)] = 1;
        }
  }
  return best;
}

/// log of the mixture density q at x: (1/n) [sum over the usable components N_i(x) + u U(x)],
/// U the uniform density over free space (log_uniform at x in it).
double log_mixture(const std::vector<Component>& comps, std::size_t uniform_draws,
                   double log_uniform, double log_n, const robot::Pose& x) {
  // A running maximum: no allocation per particle.
  double top =
      uniform_draws > 0 ? std::log(static_cast<double>(uniform_draws)) + log_uniform : kNegInf;
  double sum = uniform_draws > 0 ? 1.0 : 0.0;
  for (const Component& c : comps) {
    if (!c.ok) continue;
    const double l = log_normal(c, x);
    if (l > top) {
      sum = sum * std::exp(top - l) + 1.0;
      top = l;
    } else {
      sum += std::exp(l - top);
    }
  }
  return top + std::log(sum) - log_n;
}

}  // namespace

NewtonMinimum<SmallFactor<3>> match_scan_near(const robot::LikelihoodFieldModel& model,
                                              const robot::PreparedScan& z,
                                              const robot::Pose& start) {
  constexpr double s = 0.5;
  filter::PoseObjective<robot::LikelihoodFieldModel> f;
  f.reset(model, z, start, robot::Mat3::Identity() / (s * s), 0.0);
  return newton_minimize<SmallFactor<3>>(f, start, filter::scan_newton_options());
}

GlobalStart global_start(const robot::LikelihoodFieldModel& model, const robot::OccupancyGrid& map,
                         const robot::LaserScan& scan, std::size_t particles, bool implicit,
                         std::uint64_t seed) {
  require(particles >= 1, "global start: expected at least one particle");
  const FreeSpace space(map);
  const robot::PreparedScan z = model.prepare(scan, "the global start's scan");
  if (!implicit || !model.differentiable())
    return uniform_global_start(model, space, z, particles, seed);
  // A tenth of the particles are drawn uniformly (a defensive component: the weights stay
  // bounded where the mixture missed a mode); the rest start Newton at the coarse search's best.
  const std::size_t uniform_draws = particles / 10;
  const std::vector<robot::Pose> starts =
      best_coarse_poses(model, z, space, particles - uniform_draws);
  const std::size_t k_starts = starts.size();
  GlobalStart g;
  g.particles.resize(particles);
  g.log_weights.assign(particles, kNegInf);
  std::vector<Component> comps(k_starts);
  parallel_for(particles, [&](std::size_t k) {
    Rng rng({seed, 0, k, purpose::kGlobalInit});
    if (k >= k_starts) {
      g.particles[k] = space.draw(rng);
      return;
    }
    const robot::Pose& start = starts[k];
    const auto r = match_scan_near(model, z, start);
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
  require(usable + uniform_draws > 0,
          "global start: no start of the scan matching gave a usable minimum");
  const double log_n = std::log(static_cast<double>(usable + uniform_draws));
  const double log_uniform = space.log_density();
  parallel_for(
      particles,
      [&](std::size_t j) {
        if ((j < k_starts && !comps[j].ok) || !space.contains(g.particles[j])) return;
        // p(z | x) U(x) / q(x): the deterministic mixture's weight.
        g.log_weights[j] = model.log_likelihood(z, g.particles[j]) + log_uniform -
                           log_mixture(comps, uniform_draws, log_uniform, log_n, g.particles[j]);
      },
      4);
  return g;
}

}  // namespace implicit::experiments
