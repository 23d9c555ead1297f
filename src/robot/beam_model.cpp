#include "implicit/robot/beam_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"

namespace implicit::robot {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

/// log(e^a + e^b), exact when either is -infinity.
double log_add(double a, double b) {
  if (a < b) std::swap(a, b);
  if (b == kNegInf) return a;
  return a + std::log1p(std::exp(b - a));
}

/// log of w * e^l with w >= 0 (-infinity for w = 0).
double log_weighted(double w, double l) { return w > 0.0 ? std::log(w) + l : kNegInf; }

}  // namespace

void BeamModelParams::validate() const {
  const auto weight = [](double w, const char* name) {
    require(w >= 0 && std::isfinite(w), "beam model: expected {} >= 0, got {}", name, w);
  };
  weight(z_hit, "z_hit");
  weight(z_short, "z_short");
  weight(z_max, "z_max");
  weight(z_rand, "z_rand");
  require(z_hit > 0, "beam model: expected z_hit > 0 (the hit component carries the map), got {}",
          z_hit);
  require(sigma_hit > 0 && std::isfinite(sigma_hit),
          "beam model: expected sigma_hit > 0 [m], got {}", sigma_hit);
  require(lambda_short > 0 && std::isfinite(lambda_short),
          "beam model: expected lambda_short > 0 [1/m], got {}", lambda_short);
  require(max_beams >= 1, "beam model: expected max_beams >= 1, got {}", max_beams);
  require(!std::isnan(laser_max_range) && laser_max_range < std::numeric_limits<double>::infinity(),
          "beam model: expected a finite laser_max_range (<= 0: the scan's), got {}",
          laser_max_range);
  require(!std::isnan(laser_min_range) && laser_min_range < std::numeric_limits<double>::infinity(),
          "beam model: expected a finite laser_min_range (<= 0: the scan's), got {}",
          laser_min_range);
}

BeamModel::BeamModel(std::shared_ptr<const OccupancyGrid> map, const BeamModelParams& p,
                     const LaserMount& mount)
    : map_(std::move(map)), p_(p), mount_(mount) {
  require(map_ != nullptr && !map_->empty(), "beam model: expected an occupancy grid with cells");
  p_.validate();
  require(std::isfinite(mount.x) && std::isfinite(mount.y) && std::isfinite(mount.yaw),
          "beam model: expected a finite laser mount, got ({}, {}, {})", mount.x, mount.y,
          mount.yaw);
  log_sum_ = std::log(p_.z_hit + p_.z_short + p_.z_max + p_.z_rand);
}

std::string_view BeamModel::why_not_differentiable() const {
  return "the beam model's expected range comes from ray casting, a step function of the pose "
         "(use the likelihood field, --laser-model likelihood-field, for the implicit proposal)";
}

PreparedBeams BeamModel::prepare(const LaserScan& scan, std::string_view where) const {
  scan.validate(where);
  PreparedBeams z;
  z.z_max = p_.laser_max_range > 0 ? p_.laser_max_range : scan.range_max;
  const double z_min = p_.laser_min_range > 0 ? p_.laser_min_range : scan.range_min;
  const std::size_t n = scan.size();
  const std::size_t used = std::min<std::size_t>(n, static_cast<std::size_t>(p_.max_beams));
  z.beams.reserve(used);
  for (std::size_t k = 0; k < used; ++k) {
    const std::size_t i = evenly_spaced_beam(k, used, n);
    const double r = scan.ranges[i];
    PreparedBeams::Beam b;
    b.bearing = mount_.yaw + scan.bearing(i);
    b.no_return = r >= z.z_max || r >= scan.range_max;
    if (!b.no_return && r < z_min) {
      ++z.skipped_short;
      continue;
    }
    b.range = b.no_return ? z.z_max : r;
    z.beams.push_back(b);
  }
  return z;
}

double BeamModel::beam_log_density(double range, bool no_return, double expected,
                                   double z_max) const {
  const double s = p_.sigma_hit;
  if (no_return) {
    // The hit's Gaussian mass beyond the range, and the missed echo.
    const double tail = 0.5 * std::erfc((z_max - expected) / (s * std::sqrt(2.0)));
    return std::log(p_.z_hit * tail + p_.z_max) - log_sum_;
  }
  const double u = (range - expected) / s;
  double l = log_weighted(p_.z_hit, -0.5 * u * u - std::log(gaussian_normaliser(s)));
  if (range <= expected && expected > 0.0) {
    const double lambda = p_.lambda_short;
    l = log_add(l, log_weighted(p_.z_short, std::log(lambda) - lambda * range -
                                                std::log(-std::expm1(-lambda * expected))));
  }
  l = log_add(l, log_weighted(p_.z_rand, -std::log(z_max)));
  return l - log_sum_;
}

double BeamModel::log_likelihood(const PreparedBeams& z, const Pose& x) const {
  const double c = std::cos(x(2)), s = std::sin(x(2));
  const Vec<2> origin(x(0) + c * mount_.x - s * mount_.y, x(1) + s * mount_.x + c * mount_.y);
  if (!origin.allFinite()) return kNegInf;  // a diverged particle: weight 0, not an exception
  double sum = 0.0;
  for (const PreparedBeams::Beam& b : z.beams) {
    const double expected = cast_ray(*map_, origin, x(2) + b.bearing, z.z_max);
    sum += beam_log_density(b.range, b.no_return, expected, z.z_max);
  }
  return sum;
}

}  // namespace implicit::robot
