// Spatial grid index and the maximum-likelihood association of one detection against a map.
#include "implicit/slam/landmark_index.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::slam {

using robot::Mat2;
using robot::RangeBearingSensor;

LandmarkGridIndex::LandmarkGridIndex(double cell_size) : cell_size_(cell_size) {
  require(cell_size > 0 && std::isfinite(cell_size),
          "landmark grid index: expected a positive cell size, got {}", cell_size);
}

int LandmarkGridIndex::covariance_class(double cov_trace) {
  if (!(cov_trace > kClassTrace0)) return 0;  // also NaN: such a landmark never passes the gate
  const int c = static_cast<int>(std::ceil(std::log(cov_trace / kClassTrace0) / std::log(4.0)));
  // Round-off at a class boundary: make sure trace <= class_trace(c).
  int k = std::clamp(c, 0, kMaxClass);
  while (k < kMaxClass && cov_trace > class_trace(k)) ++k;
  return k;
}

double LandmarkGridIndex::class_trace(int c) { return kClassTrace0 * std::pow(4.0, c); }

std::int64_t LandmarkGridIndex::cell_coordinate(int c, double v) const {
  // Clamped so that far-away (or huge) coordinates cannot overflow the key.
  const double cell = std::ldexp(cell_size_, c);
  return static_cast<std::int64_t>(std::clamp(std::floor(v / cell), -1e9, 1e9));
}

std::uint64_t LandmarkGridIndex::key(int c, std::int64_t cx, std::int64_t cy) {
  // 5 bits of class, 29 bits per coordinate (cells of >= 4 m: +-1e9 m); collisions of far
  // coordinates only add candidates, which the exact scoring removes.
  return (static_cast<std::uint64_t>(c) << 58) ^
         ((static_cast<std::uint64_t>(cx) & 0x1fffffffu) << 29) ^
         (static_cast<std::uint64_t>(cy) & 0x1fffffffu);
}

void LandmarkGridIndex::insert(std::uint32_t slot, const Vec<2>& position, double cov_trace) {
  if (!position.allFinite()) return;
  const int c = covariance_class(cov_trace);
  auto& list = cells_[key(c, cell_coordinate(c, position(0)), cell_coordinate(c, position(1)))];
  if (std::find(list.begin(), list.end(), slot) != list.end()) return;
  list.push_back(slot);
  ++entries_;
  class_used_[c] = true;
  max_class_ = std::max(max_class_, c);
}

bool LandmarkGridIndex::same_bucket(const Vec<2>& a, double trace_a, const Vec<2>& b,
                                    double trace_b) const {
  const int c = covariance_class(trace_a);
  return c == covariance_class(trace_b) && cell_coordinate(c, a(0)) == cell_coordinate(c, b(0)) &&
         cell_coordinate(c, a(1)) == cell_coordinate(c, b(1));
}

double LandmarkGridIndex::cells_covering(int c, const Vec<2>& center, double radius) const {
  if (!std::isfinite(radius) || !center.allFinite()) return std::numeric_limits<double>::infinity();
  const double cell = std::ldexp(cell_size_, c);
  const double nx =
      std::floor((center(0) + radius) / cell) - std::floor((center(0) - radius) / cell) + 1.0;
  const double ny =
      std::floor((center(1) + radius) / cell) - std::floor((center(1) - radius) / cell) + 1.0;
  return nx * ny;
}

void LandmarkGridIndex::query(int c, const Vec<2>& center, double radius,
                              std::vector<std::uint32_t>& out) const {
  const std::int64_t x0 = cell_coordinate(c, center(0) - radius);
  const std::int64_t x1 = cell_coordinate(c, center(0) + radius);
  const std::int64_t y0 = cell_coordinate(c, center(1) - radius);
  const std::int64_t y1 = cell_coordinate(c, center(1) + radius);
  for (std::int64_t cx = x0; cx <= x1; ++cx)
    for (std::int64_t cy = y0; cy <= y1; ++cy) {
      const auto it = cells_.find(key(c, cx, cy));
      if (it != cells_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
    }
}

void LandmarkGridIndex::clear() {
  cells_.clear();
  entries_ = 0;
  max_class_ = -1;
  std::fill(std::begin(class_used_), std::end(class_used_), false);
}

// Why the disc is conservative. For a landmark m with covariance P (trace P <= tau), seen from f
// at range r and bearing b, the innovation covariance is S = H_x Sigma1 H_x^T + H_m P H_m^T + R.
// For any SPD S, e^T S^-1 e >= e_i^2 / S_ii, so passing the gate needs e_r^2 <= gate S_rr and
// e_b^2 <= gate S_bb. The range row of H_x is (-u, 0) and that of H_m is u, |u| = 1, so
//   S_rr <= lambda_max(Sigma1_xy) + lambda_max(P) + R_rr <= tr Sigma1_xy + tau + R_rr.
// The bearing row of H_x is (a, -1) and that of H_m is -a, |a| = 1/r; with q(x + y) <=
// 2 q(x) + 2 q(y) for a PSD quadratic form q,
//   S_bb <= (2 tr Sigma1_xy + tau) / r^2 + 2 Sigma1_bb + R_bb.
// Hence |r - z_r| <= rho_r = sqrt(gate S_rr^max), and for r >= r_lo = z_r - rho_r > 0 the bearing
// error |wrap(b - z_b)| <= rho_b = sqrt(gate S_bb^max(r_lo)). By the law of cosines about f the
// distance from m to the point q where z lands, |m - q|^2 = (r - z_r)^2 + 2 r z_r (1 - cos(b -
// z_b)) <= rho_r^2 + (z_r + rho_r) z_r rho_b^2. Without a bearing bound, |m - f| <= z_r + rho_r.
SearchDisc association_search_disc(const RangeBearingSensor& sensor, const Pose& f,
                                   const Mat<3>& sigma1, const Measurement& z,
                                   double cov_trace_bound, double gate) {
  SearchDisc d;
  const Mat2& r = sensor.noise_covariance();
  const double tr_xy = std::max(0.0, sigma1(0, 0) + sigma1(1, 1));
  const double tau = std::max(0.0, cov_trace_bound);
  const double s_rr = tr_xy + tau + r(0, 0);
  // Relative and absolute slack for round-off in the exact scoring.
  constexpr double kSlack = 1e-9;
  d.range_margin = std::sqrt(gate * s_rr) * (1.0 + kSlack) + kSlack;
  const double far = z(0) + d.range_margin;
  d.center = f.head<2>();
  d.radius = far;
  const double r_lo = z(0) - d.range_margin;
  if (r_lo > 0.0) {
    const double s_bb =
        (2.0 * tr_xy + tau) / (r_lo * r_lo) + 2.0 * std::max(0.0, sigma1(2, 2)) + r(1, 1);
    const double rho_b = std::sqrt(gate * s_bb);
    if (rho_b < kPi) {
      const double chord =
          std::sqrt(d.range_margin * d.range_margin + far * z(0) * rho_b * rho_b) * (1.0 + kSlack) +
          kSlack;
      if (chord < d.radius) {
        d.center = RangeBearingSensor::inverse(f, z);
        d.radius = chord;
      }
    }
  }
  if (!std::isfinite(d.radius) || !d.center.allFinite())
    d.radius = std::numeric_limits<double>::infinity();
  return d;
}

namespace {

// The score of one landmark: the same arithmetic for the scan and the indexed search, so that
// both return the same association bit for bit.
bool score_landmark(const RangeBearingSensor& s, const Pose& f, const Mat<3>& sigma1,
                    const Measurement& z, const LandmarkEstimate& l, double range_margin,
                    Measurement& e, Mat2& sk) {
  const double dx = l.mean(0) - f(0), dy = l.mean(1) - f(1);
  // A landmark whose range differs by more than the margin cannot pass the gate (see above).
  if (!(std::abs(std::sqrt(dx * dx + dy * dy) - z(0)) <= range_margin)) return false;
  e = RangeBearingSensor::residual(s.predict(f, l.mean), z);
  const robot::Mat23 hx = s.jacobian_pose(f, l.mean);
  const Mat2 hm = -hx.leftCols<2>();
  sk = hx * sigma1 * hx.transpose() + hm * l.cov * hm.transpose() + s.noise_covariance();
  return true;
}

double trace_bound_of(const LandmarkEstimates& map) {
  double t = 0.0;
  map.for_each([&](std::size_t, const LandmarkEstimate& l) { t = std::max(t, l.cov.trace()); });
  return t;
}

}  // namespace

robot::Association associate_scan(const LandmarkEstimates& map, const RangeBearingSensor& sensor,
                                  const Pose& f, const Mat<3>& sigma1, const Measurement& z,
                                  double gate, double cov_trace_bound) {
  const double bound = cov_trace_bound < 0.0 ? trace_bound_of(map) : cov_trace_bound;
  const double margin = association_search_disc(sensor, f, sigma1, z, bound, gate).range_margin;
  return robot::associate_max_likelihood(
      static_cast<int>(map.size()),
      [&](int k, Measurement& e, Mat2& sk) {
        return score_landmark(sensor, f, sigma1, z, map.get(static_cast<std::size_t>(k)), margin, e,
                              sk);
      },
      gate);
}

robot::Association associate_indexed(const LandmarkEstimates& map, const LandmarkGridIndex& index,
                                     const RangeBearingSensor& sensor, const Pose& f,
                                     const Mat<3>& sigma1, const Measurement& z, double gate,
                                     std::vector<std::uint32_t>& scratch) {
  const int top = index.max_class();
  if (top < 0) return {};  // nothing registered: no landmark anywhere
  // The range check uses the margin of the widest class: conservative for every candidate.
  const double margin =
      association_search_disc(sensor, f, sigma1, z, LandmarkGridIndex::class_trace(top), gate)
          .range_margin;
  // Per class, its own (smaller) disc; fall back to the scan when the discs cover too many cells.
  double cells = 0.0;
  SearchDisc discs[LandmarkGridIndex::kMaxClass + 1];
  for (int c = 0; c <= top; ++c) {
    if (!index.has_class(c)) continue;
    discs[c] =
        association_search_disc(sensor, f, sigma1, z, LandmarkGridIndex::class_trace(c), gate);
    cells += index.cells_covering(c, discs[c].center, discs[c].radius);
  }
  if (!(cells <= std::max(16.0, static_cast<double>(map.size()))))
    return associate_scan(map, sensor, f, sigma1, z, gate, LandmarkGridIndex::class_trace(top));
  scratch.clear();
  for (int c = 0; c <= top; ++c)
    if (index.has_class(c)) index.query(c, discs[c].center, discs[c].radius, scratch);
  std::sort(scratch.begin(), scratch.end());
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  // Slots of other particles' landmarks beyond this map's size are skipped; the rest are
  // scored in slot order.
  const auto end = std::lower_bound(scratch.begin(), scratch.end(), map.size());
  robot::Association a = robot::associate_max_likelihood(
      static_cast<int>(end - scratch.begin()),
      [&](int i, Measurement& e, Mat2& sk) {
        return score_landmark(sensor, f, sigma1, z, map.get(scratch[static_cast<std::size_t>(i)]),
                              margin, e, sk);
      },
      gate);
  if (a.matched()) a.index = static_cast<int>(scratch[static_cast<std::size_t>(a.index)]);
  return a;
}

}  // namespace implicit::slam
