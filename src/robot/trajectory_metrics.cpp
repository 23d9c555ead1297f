// Trajectory scoring: association, Umeyama alignment, APE, RPE, statistics and the relation
// metric (robot/trajectory_metrics.hpp).
#include "implicit/robot/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/ranges.h>
#include <Eigen/SVD>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"

namespace implicit::robot {
namespace {

constexpr double kTrajectoryMetricsDegrees = 180.0 / kPi;

/// |E - I|_F of a 4x4 rigid motion from its angle and translation: |R - I|_F^2 = 8 sin^2(a/2),
/// which keeps full precision for small angles (6 - 2 tr R would cancel).
double trajectory_metrics_full_error(const Pose3& e) {
  const double half = std::sin(0.5 * e.rotation_angle());
  return std::sqrt(8.0 * half * half + e.translation.squaredNorm());
}

void trajectory_metrics_push_error(TrajectoryErrors& out, const Pose3& e, std::size_t i,
                                   std::size_t j) {
  out.translation.push_back(e.translation.norm());
  out.rotation_deg.push_back(e.rotation_angle() * kTrajectoryMetricsDegrees);
  out.full.push_back(trajectory_metrics_full_error(e));
  out.first.push_back(i);
  out.second.push_back(j);
}

void trajectory_metrics_check_association(const TimeAssociationOptions& o) {
  require(std::isfinite(o.max_diff) && o.max_diff >= 0,
          "trajectory association: expected a finite max_diff >= 0 [s], got {}", o.max_diff);
  require(std::isfinite(o.offset), "trajectory association: expected a finite offset [s], got {}",
          o.offset);
}

/// Index of the estimated pose nearest in time (after the offset) to t within max_diff, or -1.
std::ptrdiff_t trajectory_metrics_lookup(const Trajectory& est, double t,
                                         const TimeAssociationOptions& o) {
  const double target = t - o.offset;
  const auto it = std::lower_bound(est.times.begin(), est.times.end(), target);
  std::ptrdiff_t best = -1;
  double best_diff = 0;
  for (auto c : {it - 1, it}) {
    if (c < est.times.begin() || c == est.times.end()) continue;
    const double diff = std::abs(*c + o.offset - t);
    if (diff <= o.max_diff && (best < 0 || diff < best_diff)) {
      best = c - est.times.begin();
      best_diff = diff;
    }
  }
  return best;
}

/// Umeyama (1991), Theorem and eqs. (40)-(42), in D dimensions: R = U S V^T, c = tr(D S) / var_x,
/// t = mu_y - c R mu_x, with Sigma_xy = U D V^T the covariance of y (to) against x (from).
template <int D>
void trajectory_metrics_umeyama(const std::vector<Vec<D>>& x, const std::vector<Vec<D>>& y,
                                bool with_scale, Mat<D>& rotation, Vec<D>& translation,
                                double& scale) {
  const double n = static_cast<double>(x.size());
  Vec<D> mx = Vec<D>::Zero(), my = Vec<D>::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double var_x = 0, var_y = 0;
  Mat<D> sigma = Mat<D>::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) {
    var_x += (x[i] - mx).squaredNorm();
    var_y += (y[i] - my).squaredNorm();
    sigma += (y[i] - my) * (x[i] - mx).transpose();
  }
  var_x /= n;
  var_y /= n;
  sigma /= n;
  // Coordinates near the largest double overflow in the squares; no alignment is meaningful then.
  require(std::isfinite(var_x) && std::isfinite(var_y) && sigma.allFinite(),
          "alignment: expected positions whose spread squared is finite, got a spread of {} m "
          "(estimate) and {} m (reference)",
          std::sqrt(var_x), std::sqrt(var_y));
  require(var_x > 0, "alignment: expected estimated positions that are not all equal, got {} equal",
          x.size());
  Eigen::JacobiSVD<Mat<D>> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vec<D> d = svd.singularValues();
  // The rotation is unique when rank(Sigma_xy) >= D - 1 (Umeyama's theorem); below, the
  // positions lie on a line (3-D) or a point, and any rotation about it fits as well.
  require(d(D - 2) > 1e-10 * std::sqrt(var_x * var_y),
          "alignment: expected positions that fix the rotation ({}), got singular values of the "
          "cross-covariance {} (positions on a line or a point?)",
          D == 3 ? "not all on one line" : "not all in one point", fmt::join(d, ", "));
  Mat<D> s = Mat<D>::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(D - 1, D - 1) = -1;
  rotation = svd.matrixU() * s * svd.matrixV().transpose();
  scale = with_scale ? (d.asDiagonal() * s).trace() / var_x : 1.0;
  translation = my - scale * rotation * mx;
}

}  // namespace

PosePairs associate(const Trajectory& ref, const Trajectory& est,
                    const TimeAssociationOptions& options) {
  trajectory_metrics_check_association(options);
  ref.validate("reference trajectory");
  est.validate("estimated trajectory");
  PosePairs out;
  std::vector<double> diffs;
  std::size_t k = 0;
  for (std::size_t i = 0; i < ref.size() && !est.empty(); ++i) {
    const double t = ref.times[i];
    // Nearest indices do not decrease with t, so the search resumes where it was.
    while (k + 1 < est.size() && std::abs(est.times[k + 1] + options.offset - t) <
                                     std::abs(est.times[k] + options.offset - t))
      ++k;
    const double diff = std::abs(est.times[k] + options.offset - t);
    if (!(diff <= options.max_diff)) continue;
    if (!out.est_index.empty() && out.est_index.back() == k) {
      if (!(diff < diffs.back())) continue;  // the earlier reference pose is as close: it keeps k
      out.times.pop_back();
      out.ref.pop_back();
      out.est.pop_back();
      out.ref_index.pop_back();
      out.est_index.pop_back();
      diffs.pop_back();
    }
    out.times.push_back(t);
    out.ref.push_back(ref.poses[i]);
    out.est.push_back(est.poses[k]);
    out.ref_index.push_back(i);
    out.est_index.push_back(k);
    diffs.push_back(diff);
  }
  require(out.size() > 0,
          "trajectory association: expected estimated poses within {} s of reference times, got "
          "none (reference {} poses in [{}, {}] s, estimate {} poses in [{}, {}] s after an "
          "offset of {} s)",
          options.max_diff, ref.size(), ref.empty() ? NAN : ref.times.front(),
          ref.empty() ? NAN : ref.times.back(), est.size(),
          est.empty() ? NAN : est.times.front() + options.offset,
          est.empty() ? NAN : est.times.back() + options.offset, options.offset);
  return out;
}

const char* to_string(AlignmentKind kind) {
  switch (kind) {
    case AlignmentKind::kNone:
      return "none";
    case AlignmentKind::kSe2:
      return "se2";
    case AlignmentKind::kSe3:
      return "se3";
    case AlignmentKind::kSim3:
      return "sim3";
  }
  return "?";
}

AlignmentKind alignment_kind_from_string(const std::string& text) {
  for (auto k :
       {AlignmentKind::kNone, AlignmentKind::kSe2, AlignmentKind::kSe3, AlignmentKind::kSim3})
    if (text == to_string(k)) return k;
  throw InvalidArgument(
      fmt::format("alignment: expected one of none, se2, se3, sim3, got '{}'", printable(text)));
}

const char* to_string(DeltaUnit unit) { return unit == DeltaUnit::kFrames ? "frames" : "m"; }

Pose3 Alignment::apply(const Pose3& p) const {
  Pose3 out;
  out.translation = scale * (rotation * p.translation) + translation;
  out.rotation = (Eigen::Quaterniond(rotation) * p.rotation).normalized();
  return out;
}

double Alignment::rotation_angle() const {
  Pose3 p;
  p.rotation = Eigen::Quaterniond(rotation).normalized();
  return p.rotation_angle();
}

Alignment align_umeyama(const std::vector<Vec<3>>& est, const std::vector<Vec<3>>& ref,
                        AlignmentKind kind) {
  require(est.size() == ref.size(),
          "alignment: expected as many estimated as reference positions, got {} and {}", est.size(),
          ref.size());
  for (std::size_t i = 0; i < est.size(); ++i)
    require(est[i].allFinite() && ref[i].allFinite(),
            "alignment: pair {}: expected finite positions", i);
  Alignment a;
  a.kind = kind;
  if (kind == AlignmentKind::kNone) return a;
  const std::size_t needed = kind == AlignmentKind::kSe2 ? 2 : 3;
  require(est.size() >= needed, "alignment {}: expected at least {} pose pairs, got {}",
          to_string(kind), needed, est.size());
  if (kind == AlignmentKind::kSe2) {
    std::vector<Vec<2>> x(est.size()), y(ref.size());
    double dz = 0;
    for (std::size_t i = 0; i < est.size(); ++i) {
      x[i] = est[i].head<2>();
      y[i] = ref[i].head<2>();
      dz += ref[i](2) - est[i](2);
    }
    Mat<2> r;
    Vec<2> t;
    trajectory_metrics_umeyama<2>(x, y, false, r, t, a.scale);
    a.rotation.topLeftCorner<2, 2>() = r;
    // With R about z the height separates: its best offset is the mean height difference.
    a.translation = Vec<3>(t(0), t(1), dz / static_cast<double>(est.size()));
    return a;
  }
  trajectory_metrics_umeyama<3>(est, ref, kind == AlignmentKind::kSim3, a.rotation, a.translation,
                                a.scale);
  return a;
}

Alignment align_umeyama(const PosePairs& pairs, AlignmentKind kind) {
  std::vector<Vec<3>> est(pairs.size()), ref(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    est[i] = pairs.est[i].translation;
    ref[i] = pairs.ref[i].translation;
  }
  return align_umeyama(est, ref, kind);
}

TrajectoryErrors absolute_pose_error(const PosePairs& pairs, const Alignment& alignment) {
  require(pairs.size() > 0, "absolute pose error: expected pose pairs, got none");
  TrajectoryErrors out;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    trajectory_metrics_push_error(out, pairs.ref[i].inverse() * alignment.apply(pairs.est[i]), i,
                                  i);
  return out;
}

TrajectoryErrors relative_pose_error(const PosePairs& pairs, const Alignment& alignment,
                                     const RpeOptions& options) {
  const double delta = options.delta;
  const std::size_t n = pairs.size();
  std::vector<std::pair<std::size_t, std::size_t>> ids;
  if (options.unit == DeltaUnit::kFrames) {
    require(std::isfinite(delta) && delta >= 1 && delta == std::floor(delta) && delta <= 1e9,
            "relative pose error: expected a delta in frames that is a positive integer, got {}",
            delta);
    const auto d = static_cast<std::size_t>(delta);
    for (std::size_t i = 0; i + d < n; i += options.all_pairs ? 1 : d) ids.emplace_back(i, i + d);
  } else {
    require(std::isfinite(delta) && delta > 0,
            "relative pose error: expected a delta in metres > 0, got {}", delta);
    std::vector<double> path(n, 0.0);  // along the reference
    for (std::size_t k = 1; k < n; ++k)
      path[k] = path[k - 1] + (pairs.ref[k].translation - pairs.ref[k - 1].translation).norm();
    for (std::size_t i = 0; i < n;) {
      // The first j whose path from i reaches delta (path - path[i] grows with j).
      const auto it =
          std::partition_point(path.begin() + static_cast<std::ptrdiff_t>(i), path.end(),
                               [&](double p) { return p - path[i] < delta; });
      if (it == path.end()) {
        if (!options.all_pairs) break;
        ++i;
        continue;
      }
      const auto j = static_cast<std::size_t>(it - path.begin());
      ids.emplace_back(i, j);
      i = options.all_pairs ? i + 1 : j;
    }
  }
  require(!ids.empty(),
          "relative pose error: expected pose pairs {} {} apart, got none among {} associated "
          "poses",
          delta, to_string(options.unit), n);
  TrajectoryErrors out;
  for (const auto& [i, j] : ids) {
    const Pose3 ref_rel = pairs.ref[i].inverse() * pairs.ref[j];
    const Pose3 est_rel = alignment.apply(pairs.est[i]).inverse() * alignment.apply(pairs.est[j]);
    trajectory_metrics_push_error(out, ref_rel.inverse() * est_rel, i, j);
  }
  return out;
}

namespace {

/// numpy's default quantile: linear interpolation between order statistics of sorted v.
double trajectory_metrics_quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

}  // namespace

ErrorStatistics error_statistics(const std::vector<double>& values,
                                 const StatisticsOptions& options) {
  require(!values.empty(), "error statistics: expected at least one error value, got none");
  require(options.resamples >= 0 && options.resamples <= 1000000,
          "error statistics: expected resamples in [0, 1000000], got {}", options.resamples);
  require(options.level > 0 && options.level < 1,
          "error statistics: expected a level in (0, 1), got {}", options.level);
  for (std::size_t i = 0; i < values.size(); ++i)
    require(std::isfinite(values[i]),
            "error statistics: value {}: expected a finite number, got {}", i, values[i]);
  ErrorStatistics s;
  const double n = static_cast<double>(values.size());
  s.count = values.size();
  double sum = 0, sum_sq = 0;
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0;
  for (double v : values) var += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  s.median = trajectory_metrics_quantile(sorted, 0.5);
  if (options.resamples == 0) {
    s.mean_lo = s.mean_hi = s.rmse_lo = s.rmse_hi = NAN;
    return s;
  }
  std::vector<double> means(static_cast<std::size_t>(options.resamples));
  std::vector<double> rmses(means.size());
  // Each resample has its own stream and slot: the same intervals for any thread count.
  parallel_for(means.size(), [&](std::size_t b) {
    Rng rng({.seed = options.seed, .step = b, .index = 0, .purpose = purpose::kUser + 40});
    double bs = 0, bsq = 0;
    for (std::size_t k = 0; k < values.size(); ++k) {
      const auto pick = std::min(values.size() - 1, static_cast<std::size_t>(rng.uniform() * n));
      bs += values[pick];
      bsq += values[pick] * values[pick];
    }
    means[b] = bs / n;
    rmses[b] = std::sqrt(bsq / n);
  });
  std::sort(means.begin(), means.end());
  std::sort(rmses.begin(), rmses.end());
  const double tail = 0.5 * (1.0 - options.level);
  s.mean_lo = trajectory_metrics_quantile(means, tail);
  s.mean_hi = trajectory_metrics_quantile(means, 1.0 - tail);
  s.rmse_lo = trajectory_metrics_quantile(rmses, tail);
  s.rmse_hi = trajectory_metrics_quantile(rmses, 1.0 - tail);
  return s;
}

RelationErrors relation_errors(const Trajectory& est, const std::vector<Relation>& relations,
                               const TimeAssociationOptions& options) {
  trajectory_metrics_check_association(options);
  est.validate("estimated trajectory");
  require(!est.empty(), "relation metric: expected an estimated trajectory, got no poses");
  require(!relations.empty(), "relation metric: expected at least one relation, got none");
  RelationErrors out;
  for (std::size_t r = 0; r < relations.size(); ++r) {
    const Relation& rel = relations[r];
    const std::ptrdiff_t a = trajectory_metrics_lookup(est, rel.t1, options);
    const std::ptrdiff_t b = trajectory_metrics_lookup(est, rel.t2, options);
    if (a < 0 || b < 0) {
      ++out.skipped;
      continue;
    }
    const Pose3 delta =
        est.poses[static_cast<std::size_t>(a)].inverse() * est.poses[static_cast<std::size_t>(b)];
    const Pose3 e = rel.delta.inverse() * delta;
    const double t = e.translation.norm();
    const double angle = e.rotation_angle() * kTrajectoryMetricsDegrees;
    out.translation.push_back(t);
    out.rotation_deg.push_back(angle);
    out.used.push_back(r);
    out.translation_mean += t;
    out.translation_sq_mean += t * t;
    out.rotation_mean_deg += angle;
    out.rotation_sq_mean_deg += angle * angle;
  }
  require(!out.used.empty(),
          "relation metric: expected relations whose times t1 and t2 both have an estimated pose "
          "within {} s, got none of {} (estimate in [{}, {}] s after an offset of {} s)",
          options.max_diff, relations.size(), est.times.front() + options.offset,
          est.times.back() + options.offset, options.offset);
  const double m = static_cast<double>(out.used.size());
  out.translation_mean /= m;
  out.translation_sq_mean /= m;
  out.rotation_mean_deg /= m;
  out.rotation_sq_mean_deg /= m;
  return out;
}

}  // namespace implicit::robot
