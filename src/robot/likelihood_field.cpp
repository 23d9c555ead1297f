#include "implicit/robot/likelihood_field.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <mutex>
#include <numbers>

#include "distance_field_kernels.hpp"
#include "implicit/core/gaussian.hpp"

namespace implicit::robot {
namespace {

// The constants of one scan's beam density log(e^h + c), h = log_hit_scale - d^2 / (2 sigma^2),
// c = z_rand / z_max, with d a beam's capped distance: beam_log_density() (likelihood_field.hpp).
struct BeamDensity {
  double log_hit_scale, inv_var, c;

  double log_hit(double d) const { return log_hit_scale - 0.5 * d * d * inv_var; }
  /// log(e^h + c); without the uniform term (c = 0) e^h could underflow: h itself.
  double log_beam(double d) const {
    const double h = log_hit(d);
    return c > 0.0 ? std::log(std::exp(h) + c) : h;
  }
};

// The sum over a scan's beams of their log densities log(e^h + c). As the sum of the logs is the
// log of the product, the densities e^h + c are multiplied and one log is taken at the end: a
// log per beam costs as much as the rest of a bilinear beam. The product is renormalised
// (frexp) every 8 factors; with factors in [c, e^log_hit_scale + c] it then stays a normal
// number whenever c >= 2^-120 and e^log_hit_scale <= 2^115 (any sensible parameters; others sum
// the logs). Rounding: an ulp or so per factor, relative, so n ulp in the log: as summing logs.
class BeamLogSum {
 public:
  explicit BeamLogSum(const BeamDensity& density)
      : b_(density), product_(density.c >= 0x1p-120 && density.log_hit_scale <= 79.0) {}

  void add(double d) { add_log_hit(b_.log_hit(d), nullptr); }
  /// Also gives the hit component's share of the beam's density, gamma = e^h / (e^h + c).
  double add_with_share(double d) {
    double gamma;
    add_log_hit(b_.log_hit(d), &gamma);
    return gamma;
  }
  double value() const {
    return sum_ + std::log(mantissa_) + std::numbers::ln2 * static_cast<double>(exponent_);
  }

 private:
  void add_log_hit(double h, double* gamma) {
    if (b_.c <= 0.0) {
      sum_ += h;
      if (gamma != nullptr) *gamma = 1.0;
      return;
    }
    const double hit = std::exp(h), density = hit + b_.c;
    if (gamma != nullptr) *gamma = hit / density;
    if (!product_) {
      sum_ += std::log(density);
      return;
    }
    mantissa_ *= density;
    if (++factors_ == 8) {
      int e;
      mantissa_ = std::frexp(mantissa_, &e);  // NaN stays NaN
      exponent_ += e;
      factors_ = 0;
    }
  }

  BeamDensity b_;
  bool product_;
  double sum_ = 0.0, mantissa_ = 1.0;
  std::int64_t exponent_ = 0;
  int factors_ = 0;
};

}  // namespace

// The tables of CellLogDensity by maximum range, most recent last. A log has one maximum range
// (or nav2's laser_max_range overrides it); a few are kept in case scans differ.
struct LikelihoodFieldModel::CellTables {
  static constexpr std::size_t kKept = 4;
  std::mutex mutex;
  std::vector<std::shared_ptr<const CellLogDensity>> tables;
};

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
  cell_tables_ = std::make_shared<CellTables>();
}

std::shared_ptr<const CellLogDensity> LikelihoodFieldModel::cell_log_density(double z_max) const {
  CellTables& cache = *cell_tables_;
  const std::lock_guard<std::mutex> lock(cache.mutex);
  for (const auto& t : cache.tables)
    if (t->z_max == z_max) return t;
  auto table = std::make_shared<CellLogDensity>();
  table->z_max = z_max;
  table->owner = cell_tables_.get();
  const BeamDensity density{std::log(p_.z_hit / gaussian_normaliser(p_.sigma_hit)), inv_var_,
                            p_.z_rand / z_max};
  const std::vector<float>& distances = field_->padded_;
  table->cells.resize(distances.size());
  // Runs of equal distances are common (most cells of a large map are at the cap): one
  // density per run.
  float last_distance = std::numeric_limits<float>::quiet_NaN(), last_value = 0.0f;
  for (std::size_t k = 0; k < distances.size(); ++k) {
    if (distances[k] != last_distance) {
      last_distance = distances[k];
      last_value = static_cast<float>(
          density.log_beam(std::min(static_cast<double>(last_distance), max_distance_)));
    }
    table->cells[k] = last_value;
  }
  table->outside = static_cast<float>(density.log_beam(max_distance_));
  if (cache.tables.size() == CellTables::kKept) cache.tables.erase(cache.tables.begin());
  cache.tables.push_back(table);
  return table;
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
  z.log_hit_scale = std::log(p_.z_hit / gaussian_normaliser(p_.sigma_hit));
  z.rand_density = p_.z_rand / z.z_max;
  // nav2's subsampling: max_beams beams evenly spaced from the first to the last.
  const std::size_t n = scan.size();
  const std::size_t used = std::min<std::size_t>(n, static_cast<std::size_t>(p_.max_beams));
  const double mc = std::cos(mount_.yaw), ms = std::sin(mount_.yaw);
  z.end_points.reserve(used);
  for (std::size_t k = 0; k < used; ++k) {
    const std::size_t i = evenly_spaced_beam(k, used, n);
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
  if (p_.interpolation == Interpolation::kNearest && p_.aggregation == BeamAggregation::kProduct)
    z.cell_log_density = cell_log_density(z.z_max);
  return z;
}

double LikelihoodFieldModel::log_likelihood(const PreparedScan& z, const Pose& x) const {
  if (p_.aggregation == BeamAggregation::kCubedSum) return cubed_sum_log_likelihood(z, x);
  switch (p_.interpolation) {
    case Interpolation::kNearest:
      // The table, unless z was prepared by another model (then its constants are used as they
      // are, as for the other modes).
      if (z.cell_log_density != nullptr && z.cell_log_density->owner == cell_tables_.get())
        return nearest_log_likelihood(z, x);
      return interpolated_log_likelihood<Interpolation::kNearest>(z, x);
    case Interpolation::kBilinear:
      return interpolated_log_likelihood<Interpolation::kBilinear>(z, x);
    case Interpolation::kBicubic:
      return interpolated_log_likelihood<Interpolation::kBicubic>(z, x);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double LikelihoodFieldModel::nearest_log_likelihood(const PreparedScan& z, const Pose& x) const {
  const detail::FieldLookup f = field_->lookup();
  const float* cells = z.cell_log_density->cells.data();
  const double outside = z.cell_log_density->outside;
  // Grid coordinates straight from the end points: u = u0 + (c e_x - s e_y) / resolution.
  const double c = std::cos(x(2)) * f.inv_resolution, s = std::sin(x(2)) * f.inv_resolution;
  const double u0 = f.grid_u(x(0)), v0 = f.grid_v(x(1));
  const auto beam = [&](const Vec<2>& e) -> double {
    const double u = u0 + c * e(0) - s * e(1), v = v0 + s * e(0) + c * e(1);
    if (f.interpolates_at(u, v)) return cells[f.cell_index(u, v)];
    return std::isnan(u) || std::isnan(v) ? std::numeric_limits<double>::quiet_NaN() : outside;
  };
  // Two sums, so that consecutive beams do not wait for each other's addition.
  const std::vector<Vec<2>>& e = z.end_points;
  const std::size_t n = e.size();
  double even = 0.0, odd = 0.0;
  std::size_t i = 0;
  for (; i + 1 < n; i += 2) {
    even += beam(e[i]);
    odd += beam(e[i + 1]);
  }
  if (i < n) even += beam(e[i]);
  return even + odd;
}

template <Interpolation Mode>
double LikelihoodFieldModel::interpolated_log_likelihood(const PreparedScan& z,
                                                         const Pose& x) const {
  const detail::FieldLookup f = field_->lookup();
  const BeamDensity density{z.log_hit_scale, inv_var_, z.rand_density};
  const double c = std::cos(x(2)), s = std::sin(x(2));
  BeamLogSum total(density);
  for (const Vec<2>& e : z.end_points) {
    const double u = f.grid_u(x(0) + c * e(0) - s * e(1));
    const double v = f.grid_v(x(1) + s * e(0) + c * e(1));
    const double d = f.interpolates_at(u, v) ? f.interpolate<Mode, false>(u, v, nullptr, nullptr)
                                             : field_->outside(u, v, nullptr);
    total.add(std::min(d, max_distance_));
  }
  return total.value();
}

double LikelihoodFieldModel::cubed_sum_log_likelihood(const PreparedScan& z, const Pose& x) const {
  const double c = std::cos(x(2)), s = std::sin(x(2));
  double sum = 1.0;
  for (const Vec<2>& e : z.end_points) {
    const Vec<2> p(x(0) + c * e(0) - s * e(1), x(1) + s * e(0) + c * e(1));
    const double d = std::min(field_->distance(p, p_.interpolation), max_distance_);
    const double pz = p_.z_hit * std::exp(-0.5 * d * d * inv_var_) + z.rand_density;
    sum += pz * pz * pz;
  }
  return std::log(sum);
}

double LikelihoodFieldModel::negative_log_likelihood(const PreparedScan& z, const Pose& x,
                                                     Vec<3>* gradient, Mat3* gauss_newton) const {
  switch (p_.interpolation) {
    case Interpolation::kNearest:
      return interpolated_negative_log_likelihood<Interpolation::kNearest>(z, x, gradient,
                                                                           gauss_newton);
    case Interpolation::kBilinear:
      return interpolated_negative_log_likelihood<Interpolation::kBilinear>(z, x, gradient,
                                                                            gauss_newton);
    case Interpolation::kBicubic:
      return interpolated_negative_log_likelihood<Interpolation::kBicubic>(z, x, gradient,
                                                                           gauss_newton);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

template <Interpolation Mode>
double LikelihoodFieldModel::interpolated_negative_log_likelihood(const PreparedScan& z,
                                                                  const Pose& x, Vec<3>* gradient,
                                                                  Mat3* gauss_newton) const {
  if (gradient == nullptr && gauss_newton == nullptr)
    return -interpolated_log_likelihood<Mode>(z, x);
  const detail::FieldLookup f = field_->lookup();
  const BeamDensity density{z.log_hit_scale, inv_var_, z.rand_density};
  const double c = std::cos(x(2)), s = std::sin(x(2));
  BeamLogSum log_p(density);
  Vec<3> g = Vec<3>::Zero();
  Mat3 h = Mat3::Zero();
  for (const Vec<2>& e : z.end_points) {
    // Offset of the end point from the robot in the world frame: d p / d heading = (-oy, ox).
    const double ox = c * e(0) - s * e(1), oy = s * e(0) + c * e(1);
    const double u = f.grid_u(x(0) + ox), v = f.grid_v(x(1) + oy);
    Vec<2> grad_d;  // per metre
    double d;
    if (f.interpolates_at(u, v)) {
      double du, dv;
      d = f.interpolate<Mode, true>(u, v, &du, &dv);
      grad_d = Vec<2>(du * f.inv_resolution, dv * f.inv_resolution);
    } else {
      d = field_->outside(u, v, &grad_d);
    }
    if (d >= max_distance_) {  // capped: constant in x
      d = max_distance_;
      grad_d.setZero();
    }
    // gamma: the hit component's share; d(-log p)/dd = gamma d / sigma^2.
    const double gamma = log_p.add_with_share(d);
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
  return -log_p.value();
}

}  // namespace implicit::robot
