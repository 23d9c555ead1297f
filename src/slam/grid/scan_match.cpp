#include "implicit/slam/grid/scan_match.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"

namespace implicit::slam {

namespace {

constexpr int kScanMatchMaxTaps = 4 * ScanMatchParams::kMaxSmoothing;

// The cubic B-spline (support |u| < 2, integral 1) and its first two derivatives. Integer
// spacings 1/s sum to s at every u, so B(u)/s over the cell centres is a partition of unity: M
// is a convex combination of the cells' occupancy evidence.
inline void scan_match_bspline(double u, double& b, double& db, double& d2b) {
  const double a = std::abs(u);
  const double sign = u < 0 ? -1.0 : 1.0;
  if (a < 1.0) {
    b = 2.0 / 3.0 - a * a + 0.5 * a * a * a;
    db = sign * (-2.0 * a + 1.5 * a * a);
    d2b = -2.0 + 3.0 * a;
  } else if (a < 2.0) {
    const double m = 2.0 - a;
    b = m * m * m / 6.0;
    db = -sign * 0.5 * m * m;
    d2b = m;
  } else {
    b = db = d2b = 0.0;
  }
}

// Kernel weights along one axis for world coordinate p: taps cells first..first + taps - 1, with
// the weights' derivatives in p.
struct ScanMatchTaps {
  int first = 0, taps = 0;
  std::array<double, kScanMatchMaxTaps> w{}, dw{}, d2w{};
};

inline void scan_match_taps(double p, double resolution, int s, bool derivatives,
                            ScanMatchTaps& t) {
  const double q = p / resolution - 0.5;  // in cell-centre units
  const double sd = static_cast<double>(s);
  t.first = static_cast<int>(std::floor(q - 2.0 * sd)) + 1;
  t.taps = 4 * s;
  const double inv_s = 1.0 / sd, du = 1.0 / (sd * resolution);
  for (int i = 0; i < t.taps; ++i) {
    double b = 0, db = 0, d2b = 0;
    scan_match_bspline((q - (t.first + i)) * inv_s, b, db, d2b);
    t.w[static_cast<std::size_t>(i)] = b * inv_s;
    if (derivatives) {
      t.dw[static_cast<std::size_t>(i)] = db * inv_s * du;
      t.d2w[static_cast<std::size_t>(i)] = d2b * inv_s * du * du;
    }
  }
}

}  // namespace

void ScanMatchParams::validate() const {
  require(max_beams >= 1, "ScanMatchParams: expected max_beams >= 1, got {}", max_beams);
  require(std::isfinite(floor) && floor > 0.0 && floor < 1.0,
          "ScanMatchParams: expected floor in (0, 1), got {}", floor);
  require(smoothing >= 1 && smoothing <= kMaxSmoothing,
          "ScanMatchParams: expected smoothing in [1, {}] cells, got {}", kMaxSmoothing, smoothing);
  require(!std::isnan(max_range) && max_range < std::numeric_limits<double>::infinity(),
          "ScanMatchParams: expected a finite max_range [m] (<= 0: the scan's range_max), got {}",
          max_range);
}

GridScanModel::GridScanModel(const TiledLogOddsGrid& map, const ScanMatchParams& params,
                             const robot::LaserMount& mount)
    : map_(&map), params_(params), mount_(mount) {
  params.validate();
  require(std::isfinite(mount.x) && std::isfinite(mount.y) && std::isfinite(mount.yaw),
          "GridScanModel: expected a finite laser mount, got ({}, {}, {})", mount.x, mount.y,
          mount.yaw);
}

GridScanModel GridScanModel::unchecked(const TiledLogOddsGrid& map, const ScanMatchParams& params,
                                       const robot::LaserMount& mount) {
  GridScanModel m;
  m.map_ = &map;
  m.params_ = params;
  m.mount_ = mount;
  return m;
}

ScanMatchBeams GridScanModel::prepare(const robot::LaserScan& scan, std::string_view where) const {
  ScanMatchBeams out;
  prepare_into(scan, where, out);
  return out;
}

void GridScanModel::prepare_into(const robot::LaserScan& scan, std::string_view where,
                                 ScanMatchBeams& out) const {
  scan.validate(where);
  const double range_max =
      params_.max_range > 0.0 ? std::min(params_.max_range, scan.range_max) : scan.range_max;
  const auto used_beam = [&](std::size_t i) {
    return scan.is_hit(i) && scan.ranges[i] < range_max;
  };
  std::size_t hits = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) hits += used_beam(i);
  const std::size_t used = std::min(hits, static_cast<std::size_t>(params_.max_beams));
  out.end_points.clear();
  out.end_points.reserve(used);
  std::size_t hit = 0, k = 0;
  for (std::size_t i = 0; i < scan.size() && k < used; ++i) {
    if (!used_beam(i)) continue;
    if (hit++ != robot::evenly_spaced_beam(k, used, hits)) continue;
    ++k;
    const double angle = mount_.yaw + scan.bearing(i), r = scan.ranges[i];
    out.end_points.emplace_back(mount_.x + r * std::cos(angle), mount_.y + r * std::sin(angle));
  }
}

double GridScanModel::smoothed_occupancy(const Vec<2>& p, Vec<2>* gradient,
                                         robot::Mat2* hessian) const {
  const bool derivatives = gradient != nullptr || hessian != nullptr;
  ScanMatchTaps tx, ty;
  scan_match_taps(p.x(), map_->resolution(), params_.smoothing, derivatives, tx);
  scan_match_taps(p.y(), map_->resolution(), params_.smoothing, derivatives, ty);
  double m = 0, gx = 0, gy = 0, hxx = 0, hxy = 0, hyy = 0;
  for (int j = 0; j < ty.taps; ++j) {
    const auto jj = static_cast<std::size_t>(j);
    double r0 = 0, r1 = 0, r2 = 0;  // the row's sums with w, dw and d2w along x
    for (int i = 0; i < tx.taps; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      // Occupancy evidence: 1 for a cell with enough echoes, else 2P - 1 = tanh(l / 2) where
      // positive and 0 elsewhere (free and unknown alike): a wall seen once (P = 0.7) must
      // stand out from the unknown space behind it.
      const double prob = map_->occupancy_evidence(tx.first + i, ty.first + j);
      r0 += tx.w[ii] * prob;
      if (derivatives) {
        r1 += tx.dw[ii] * prob;
        r2 += tx.d2w[ii] * prob;
      }
    }
    m += ty.w[jj] * r0;
    if (derivatives) {
      gx += ty.w[jj] * r1;
      gy += ty.dw[jj] * r0;
      hxx += ty.w[jj] * r2;
      hxy += ty.dw[jj] * r1;
      hyy += ty.d2w[jj] * r0;
    }
  }
  if (gradient) *gradient = Vec<2>(gx, gy);
  if (hessian) *hessian << hxx, hxy, hxy, hyy;
  return m;
}

// Per beam, with P = eps + a M (a = 1 - eps) and p = t + R e:
//   -log P;  gradient in p: g = -a grad M / P;  Hessian in p: -a hess M / P + (a/P)^2 gM gM^T;
// in the pose, with d = dp/dtheta = (-(Re)_y, (Re)_x) and d2p/dtheta2 = -Re (spec §3.13.1):
//   grad = (g, g.d),  H = J^T H_p J + (g . -Re) e_theta e_theta^T,  J = [I | d].
// The Gauss-Newton matrix keeps the outer-product part: J^T (a/P)^2 gM gM^T J (PSD).
double GridScanModel::negative_log_likelihood(const ScanMatchBeams& z, const robot::Pose& x,
                                              Vec<3>* gradient, robot::Mat3* hessian,
                                              robot::Mat3* gauss_newton) const {
  const double eps = params_.floor, a = 1.0 - eps;
  const double c = std::cos(x(2)), s = std::sin(x(2));
  const bool first = gradient || hessian || gauss_newton;
  const bool second = hessian != nullptr;
  double value = 0.0;
  Vec<2> gm;
  robot::Mat2 hm;
  for (const Vec<2>& e : z.end_points) {
    const Vec<2> re(c * e.x() - s * e.y(), s * e.x() + c * e.y());
    const Vec<2> p(x(0) + re.x(), x(1) + re.y());
    const double m = smoothed_occupancy(p, first ? &gm : nullptr, second ? &hm : nullptr);
    const double prob = eps + a * m;
    value -= std::log(prob);
    if (!first) continue;
    const double k = a / prob;
    const Vec<2> g = -k * gm;
    const Vec<2> d(-re.y(), re.x());
    if (gradient) *gradient += Vec<3>(g.x(), g.y(), g.dot(d));
    const robot::Mat2 outer = (k * k) * gm * gm.transpose();
    const auto add_pose = [&](const robot::Mat2& hp, double extra, robot::Mat3& out) {
      const Vec<2> hd = hp * d;
      out.topLeftCorner<2, 2>() += hp;
      out.topRightCorner<2, 1>() += hd;
      out.bottomLeftCorner<1, 2>() += hd.transpose();
      out(2, 2) += d.dot(hd) + extra;
    };
    if (gauss_newton) add_pose(outer, 0.0, *gauss_newton);
    if (hessian) add_pose(outer - k * hm, -g.dot(re), *hessian);
  }
  return value;
}

}  // namespace implicit::slam
