// Running SLAM estimators and the metrics of spec §4.
#include "implicit/slam/evaluate.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::slam {

double RigidTransform2::angle() const { return std::atan2(rotation(1, 0), rotation(0, 0)); }

RigidTransform2 align_rigid(const std::vector<Vec<2>>& from, const std::vector<Vec<2>>& to) {
  require(from.size() == to.size(), "rigid alignment: expected equal point counts, got {} and {}",
          from.size(), to.size());
  RigidTransform2 t;
  if (from.empty()) return t;
  Vec<2> mf = Vec<2>::Zero(), mt = Vec<2>::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    mf += from[i];
    mt += to[i];
  }
  mf /= static_cast<double>(from.size());
  mt /= static_cast<double>(from.size());
  Mat<2> c = Mat<2>::Zero();  // cross-covariance sum (to - mt)(from - mf)^T
  for (std::size_t i = 0; i < from.size(); ++i) c += (to[i] - mt) * (from[i] - mf).transpose();
  if (from.size() >= 2) {
    const Eigen::JacobiSVD<Mat<2>> svd(c, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat<2> d = Mat<2>::Identity();
    if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(1, 1) = -1.0;
    t.rotation = svd.matrixU() * d * svd.matrixV().transpose();
  }
  t.translation = mt - t.rotation * mf;
  return t;
}

SlamRun run_filter(const SlamDataset& data, const SlamOptions& options, bool known_map,
                   const std::function<void()>& on_step) {
  data.validate();
  SlamRun run;
  auto filter = make_slam_filter(options, data.initial_pose);
  if (known_map) filter->set_known_map(data.landmarks);
  run.path.reserve(data.steps() + 1);
  run.path_cov.reserve(data.steps() + 1);
  run.path.push_back(data.initial_pose);
  run.path_cov.push_back(Mat<3>::Zero());
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t n = 1; n <= data.steps(); ++n) {
    if (!data.step_dt.empty()) filter->set_step_length(data.step_dt[n - 1]);
    filter->step(n, data.control(n), data.observations(n));
    const PoseEstimate e = filter->pose();
    run.path.push_back(e.mean);
    run.path_cov.push_back(e.cov);
    if (on_step) on_step();
  }
  run.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.map = filter->map();
  run.stats = filter->stats();
  run.map_bytes = filter->map_bytes();
  return run;
}

SlamMetrics evaluate(const SlamDataset& data, const SlamRun& run) {
  SlamMetrics m;
  require(run.path.size() == data.steps() + 1, "SLAM metrics: expected a path of {} poses, got {}",
          data.steps() + 1, run.path.size());
  m.landmarks = run.map.landmarks.size();
  // Map correspondence.
  std::vector<Vec<2>> est, tru;
  if (!data.landmarks.empty()) {
    for (std::size_t k = 0; k < run.map.landmarks.size(); ++k) {
      const int id = run.map.ids[k];
      if (id >= 0 && static_cast<std::size_t>(id) < data.landmarks.size()) {
        est.push_back(run.map.landmarks[k]);
        tru.push_back(data.landmarks[static_cast<std::size_t>(id)]);
      } else if (id < 0) {
        std::size_t best = 0;
        double bd = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < data.landmarks.size(); ++i) {
          const double d = (data.landmarks[i] - run.map.landmarks[k]).squaredNorm();
          if (d < bd) {
            bd = d;
            best = i;
          }
        }
        est.push_back(run.map.landmarks[k]);
        tru.push_back(data.landmarks[best]);
      }
    }
  }
  // Path with truth.
  std::vector<Vec<2>> path_est, path_true;
  double num = 0.0, den = 0.0, head = 0.0;
  std::size_t count = 0;
  m.nees.assign(run.path.size(), std::numeric_limits<double>::quiet_NaN());
  double nees_sum = 0.0;
  for (std::size_t n = 1; n < run.path.size(); ++n) {
    if (!data.has_truth(n)) continue;
    const Pose& t = data.truth[n];
    const Pose& e = run.path[n];
    num += (e.head<2>() - t.head<2>()).squaredNorm();
    den += t.head<2>().squaredNorm();
    path_est.push_back(e.head<2>());
    path_true.push_back(t.head<2>());
    ++count;
    if (data.truth_has_heading) {
      const double dh = wrap_angle(e(2) - t(2));
      head += dh * dh;
      Vec<3> d(e(0) - t(0), e(1) - t(1), dh);
      const Eigen::LLT<Mat<3>> llt(run.path_cov[n]);
      if (llt.info() == Eigen::Success && run.path_cov[n].diagonal().minCoeff() > 0) {
        const double v = d.dot(llt.solve(d));
        if (std::isfinite(v)) {
          m.nees[n] = v;
          nees_sum += v;
          ++m.nees_steps;
        }
      }
    }
  }
  m.scored_steps = count;
  if (count == 0) {
    // Nothing to compare with: NaN (null in JSON), not an error of 0 that looks like a result.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.error_percent = m.error_aligned_percent = m.rmse_pose_m = m.rmse_pose_aligned_m = nan;
    m.rmse_heading_rad = nan;
  } else {
    m.error_percent = 100.0 * std::sqrt(num) / std::sqrt(den);
    m.rmse_pose_m = std::sqrt(num / static_cast<double>(count));
    m.rmse_heading_rad = data.truth_has_heading ? std::sqrt(head / static_cast<double>(count)) : 0;
  }
  m.nees_mean = m.nees_steps > 0 ? nees_sum / static_cast<double>(m.nees_steps)
                                 : std::numeric_limits<double>::quiet_NaN();
  if (data.landmarks.empty()) {
    // No true map (Victoria Park, GPS only): NaN (null in JSON, "n/a" in text), not an error of 0.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.rmse_map_m = m.map_shape_m = m.map_error_percent = nan;
  }
  RigidTransform2 align;
  if (est.size() >= 2) {
    double raw = 0.0, fro = 0.0;
    for (std::size_t i = 0; i < est.size(); ++i) {
      raw += (est[i] - tru[i]).squaredNorm();
      fro += tru[i].squaredNorm();
    }
    m.rmse_map_m = std::sqrt(raw / static_cast<double>(est.size()));
    m.map_error_percent = 100.0 * std::sqrt(raw / fro);
    align = align_rigid(est, tru);
    double shape = 0.0;
    for (std::size_t i = 0; i < est.size(); ++i)
      shape += (align.apply(est[i]) - tru[i]).squaredNorm();
    m.map_shape_m = std::sqrt(shape / static_cast<double>(est.size()));
  } else if (path_est.size() >= 2) {
    align = align_rigid(path_est, path_true);
  }
  m.alignment_angle_rad = align.angle();
  if (count > 0) {
    double an = 0.0;
    for (std::size_t i = 0; i < path_est.size(); ++i)
      an += (align.apply(path_est[i]) - path_true[i]).squaredNorm();
    m.error_aligned_percent = 100.0 * std::sqrt(an) / std::sqrt(den);
    m.rmse_pose_aligned_m = std::sqrt(an / static_cast<double>(count));
  }
  return m;
}

double chi_square_quantile(double p, double k) {
  require(p > 0 && p < 1 && k > 0, "chi-square quantile: expected 0 < p < 1 and k > 0");
  // Standard normal quantile (Acklam's rational approximation, |rel err| < 1.2e-9).
  const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                      1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                      6.680131188771972e+01, -1.328068155288572e+01};
  const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                      -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                      3.754408661907416e+00};
  double z;
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    z = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p > 1 - 0.02425) {
    const double q = std::sqrt(-2 * std::log(1 - p));
    z = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else {
    const double q = p - 0.5, r = q * q;
    z = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  }
  const double h = 2.0 / (9.0 * k);
  const double w = 1.0 - h + z * std::sqrt(h);
  return k * w * w * w;
}

}  // namespace implicit::slam
