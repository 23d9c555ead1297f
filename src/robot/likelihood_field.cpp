#include "implicit/robot/likelihood_field.hpp"

#include <algorithm>
#include <limits>

namespace implicit::robot {

void LikelihoodFieldParams::validate() const {
  require(z_hit > 0 && std::isfinite(z_hit), "likelihood field: expected z_hit > 0, got {}", z_hit);
  require(z_rand >= 0 && std::isfinite(z_rand), "likelihood field: expected z_rand >= 0, got {}",
          z_rand);
  require(sigma_hit > 0 && std::isfinite(sigma_hit),
          "likelihood field: expected sigma_hit > 0 [m], got {}", sigma_hit);
  require(laser_likelihood_max_dist > 0 && std::isfinite(laser_likelihood_max_dist),
          "likelihood field: expected laser_likelihood_max_dist > 0 [m], got {}",
          laser_likelihood_max_dist);
  require(max_beams >= 1, "likelihood field: expected max_beams >= 1, got {}", max_beams);
  require(!std::isnan(laser_max_range) && laser_max_range < std::numeric_limits<double>::infinity(),
          "likelihood field: expected a finite laser_max_range (<= 0: the scan's), got {}",
          laser_max_range);
  require(!std::isnan(laser_min_range) && laser_min_range < std::numeric_limits<double>::infinity(),
          "likelihood field: expected a finite laser_min_range (<= 0: the scan's), got {}",
          laser_min_range);
}

LikelihoodFieldModel::LikelihoodFieldModel(std::shared_ptr<const DistanceField> field,
                                           const LikelihoodFieldParams& p, const LaserMount& mount)
    : field_(std::move(field)), p_(p), mount_(mount) {
  require(field_ != nullptr, "likelihood field: expected a distance field, got none");
  p_.validate();
  require(std::isfinite(mount.x) && std::isfinite(mount.y) && std::isfinite(mount.yaw),
          "likelihood field: expected a finite laser mount, got ({}, {}, {})", mount.x, mount.y,
          mount.yaw);
  max_distance_ = std::min(p_.laser_likelihood_max_dist, field_->max_distance());
  inv_var_ = 1.0 / (p_.sigma_hit * p_.sigma_hit);
}

std::string_view LikelihoodFieldModel::why_not_differentiable() const {
  if (p_.aggregation != BeamAggregation::kProduct)
    return "the cubed-sum beam aggregation (1 + sum p^3) is not a likelihood";
  if (p_.interpolation == Interpolation::kNearest)
    return "nearest-cell interpolation has no gradient (use bilinear or bicubic)";
  return "";
}

PreparedScan LikelihoodFieldModel::prepare(const LaserScan& scan, std::string_view where) const {
  scan.validate(where);
  PreparedScan z;
  z.z_max = p_.laser_max_range > 0 ? p_.laser_max_range : scan.range_max;
  const double z_min = p_.laser_min_range > 0 ? p_.laser_min_range : scan.range_min;
  z.log_hit_scale = std::log(p_.z_hit / (std::sqrt(2.0 * kPi) * p_.sigma_hit));
  z.rand_density = p_.z_rand / z.z_max;
  // nav2's subsampling: max_beams beams evenly spaced from the first to the last.
  const std::size_t n = scan.size();
  const std::size_t used = std::min<std::size_t>(n, static_cast<std::size_t>(p_.max_beams));
  const double step = used > 1 ? static_cast<double>(n - 1) / static_cast<double>(used - 1) : 0.0;
  const double mc = std::cos(mount_.yaw), ms = std::sin(mount_.yaw);
  z.end_points.reserve(used);
  for (std::size_t k = 0; k < used; ++k) {
    const auto i = static_cast<std::size_t>(std::lround(static_cast<double>(k) * step));
    const double r = scan.ranges[i];
    if (r >= z.z_max || r >= scan.range_max) {
      ++z.skipped_no_return;
      continue;
    }
    if (r < z_min) {
      ++z.skipped_short;
      continue;
    }
    const double b = scan.bearing(i);
    const double sx = r * std::cos(b), sy = r * std::sin(b);
    z.end_points.emplace_back(mount_.x + mc * sx - ms * sy, mount_.y + ms * sx + mc * sy);
  }
  return z;
}

double LikelihoodFieldModel::log_likelihood(const PreparedScan& z, const Pose& x) const {
  const double c = std::cos(x(2)), s = std::sin(x(2));
  const DistanceField& field = *field_;
  if (p_.aggregation == BeamAggregation::kCubedSum) {
    double sum = 1.0;
    for (const Vec<2>& e : z.end_points) {
      const Vec<2> p(x(0) + c * e(0) - s * e(1), x(1) + s * e(0) + c * e(1));
      const double d = std::min(field.distance(p, p_.interpolation), max_distance_);
      const double pz = p_.z_hit * std::exp(-0.5 * d * d * inv_var_) + z.rand_density;
      sum += pz * pz * pz;
    }
    return std::log(sum);
  }
  double total = 0.0;
  for (const Vec<2>& e : z.end_points) {
    const Vec<2> p(x(0) + c * e(0) - s * e(1), x(1) + s * e(0) + c * e(1));
    total += beam_log_density(z, std::min(field.distance(p, p_.interpolation), max_distance_));
  }
  return total;
}

double LikelihoodFieldModel::negative_log_likelihood(const PreparedScan& z, const Pose& x,
                                                     Vec<3>* gradient, Mat3* gauss_newton) const {
  const double c = std::cos(x(2)), s = std::sin(x(2));
  const DistanceField& field = *field_;
  const bool derivatives = gradient != nullptr || gauss_newton != nullptr;
  double value = 0.0;
  Vec<3> g = Vec<3>::Zero();
  Mat3 h = Mat3::Zero();
  for (const Vec<2>& e : z.end_points) {
    // Offset of the end point from the robot in the world frame: d p / d heading = (-oy, ox).
    const double ox = c * e(0) - s * e(1), oy = s * e(0) + c * e(1);
    Vec<2> grad_d;
    double d = field.distance(Vec<2>(x(0) + ox, x(1) + oy), p_.interpolation,
                              derivatives ? &grad_d : nullptr);
    if (d >= max_distance_) {  // capped: constant in x
      d = max_distance_;
      grad_d.setZero();
    }
    const double log_hit = z.log_hit_scale - 0.5 * d * d * inv_var_;
    const double log_beam = beam_log_density(z, d);
    value -= log_beam;
    if (!derivatives) continue;
    // gamma: the hit component's share; d(-log p)/dd = gamma d / sigma^2.
    const double gamma = std::exp(log_hit - log_beam);
    const double jx = grad_d(0), jy = grad_d(1), jt = -grad_d(0) * oy + grad_d(1) * ox;
    const double slope = gamma * d * inv_var_;
    g(0) += slope * jx;
    g(1) += slope * jy;
    g(2) += slope * jt;
    const double w = gamma * inv_var_;
    h(0, 0) += w * jx * jx;
    h(0, 1) += w * jx * jy;
    h(0, 2) += w * jx * jt;
    h(1, 1) += w * jy * jy;
    h(1, 2) += w * jy * jt;
    h(2, 2) += w * jt * jt;
  }
  if (gradient) *gradient += g;
  if (gauss_newton) {
    h(1, 0) = h(0, 1);
    h(2, 0) = h(0, 2);
    h(2, 1) = h(1, 2);
    *gauss_newton += h;
  }
  return value;
}

}  // namespace implicit::robot
