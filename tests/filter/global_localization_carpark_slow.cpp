// Global localization on the Car Park: the modes of the first scan with at least two detections
// include the GPS position; the numbers (starts, modes, time, ESS) are printed for the record.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "implicit/core/weights.hpp"
#include "implicit/filter/global_localization.hpp"
#include "implicit/robot/carpark.hpp"

namespace implicit::filter {
namespace {

TEST(GlobalLocalizationCarPark, ModesOfFirstScanIncludeGpsPosition) {
  const robot::UteModel model;
  const robot::RangeBearingSensor sensor;
  const robot::RobotLog log =
      robot::carpark_to_log(robot::load_carpark(robot::default_carpark_dir()), model);
  // The first scan at or after the first GPS fix with >= 2 detections, inside the GPS record.
  const robot::ObservationSet* scan = nullptr;
  for (const auto& s : log.scans)
    if (s.time >= log.truth.front().time && s.observations.size() >= 2) {
      scan = &s;
      break;
    }
  ASSERT_NE(scan, nullptr);
  std::size_t i = 1;
  while (i < log.truth.size() && log.truth[i].time < scan->time) ++i;
  ASSERT_LT(i, log.truth.size());
  const auto& a = log.truth[i - 1];
  const auto& b = log.truth[i];
  const double f = (scan->time - a.time) / (b.time - a.time);
  const Vec<2> truth = a.position + f * (b.position - a.position);

  std::vector<LabelledMeasurement> z;
  for (const auto& o : scan->observations) z.push_back({o.z, o.landmark_id});
  const robot::LandmarkObservation<robot::RangeBearingSensor> observation(sensor, log.landmarks);
  const auto ctx = observation.view(z);

  const GlobalInitOptions options;
  const PoseBounds bounds = map_bounds(observation.landmarks(), options.margin);
  GlobalInitStats st;
  const auto t0 = std::chrono::steady_clock::now();
  const auto modes = find_pose_modes(ctx, bounds, options, &st);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_FALSE(modes.empty());
  std::size_t nearest = 0;
  for (std::size_t k = 1; k < modes.size(); ++k)
    if ((modes[k].mu.head<2>() - truth).norm() < (modes[nearest].mu.head<2>() - truth).norm())
      nearest = k;
  const double distance = (modes[nearest].mu.head<2>() - truth).norm();
  // GPS sits at the laser point to ~0.1 m; the range noise std is 0.22 m.
  EXPECT_LT(distance, 1.0);

  const MixtureProposal<3> mix(modes);
  constexpr std::size_t kN = 10000;
  std::vector<Pose> x(kN);
  std::vector<double> lw(kN);
  sample_pose_mixture(ctx, modes, bounds, 1, 0, x, lw);
  std::vector<double> w(kN);
  const WeightSummary ws = normalize_log_weights(lw, w);
  const double ess = ws.ess;
  // Every detection's likelihood is at least p0, so log Z >= n log p0 (the all-clutter floor).
  const double floor = static_cast<double>(z.size()) * observation.log_clutter();
  std::vector<double> lw_defensive(kN);
  sample_pose_mixture(ctx, modes, bounds, 1, 0, x, lw_defensive, 0.5);
  const WeightSummary wd = normalize_log_weights(lw_defensive, w);
  // One-sided check of the defensive estimate against the bound: mean + 4.5 SE >= p0^n.
  double sum = 0.0, sum2 = 0.0;
  for (const double l : lw_defensive) {
    const double v = std::exp(l - floor);  // weights in units of p0^n
    sum += v;
    sum2 += v * v;
  }
  const double n = static_cast<double>(kN), mean = sum / n;
  const double se = std::sqrt((sum2 / n - mean * mean) / (n - 1.0));
  EXPECT_GE(mean + 4.5 * se, 1.0);
  std::printf(
      "log Z >= n log p0 = %.4f; half the draws uniform: log mean weight %.4f (relative SE %.2g), "
      "ESS %.0f\n",
      floor, wd.log_mean, se / mean, wd.ess);
  std::printf(
      "scan t=%.3f s, %zu detections; box [%.1f, %.1f] x [%.1f, %.1f]; starts %zu, skipped %zu, "
      "converged %zu, degenerate %zu, negligible %zu, modes %zu, evaluations %ld, %.3f s; "
      "nearest mode to GPS: rank %zu by phi, %.3f m, pi %.3g (largest %.3g); ESS %.0f of %zu, log "
      "mean weight %.4f\n",
      scan->time, z.size(), bounds.x_min, bounds.x_max, bounds.y_min, bounds.y_max, st.starts,
      st.skipped, st.converged, st.degenerate, st.negligible, st.modes, st.evaluations, seconds,
      nearest, distance, std::exp(mix.log_mixture_weights()[nearest]),
      std::exp(
          *std::max_element(mix.log_mixture_weights().begin(), mix.log_mixture_weights().end())),
      ess, kN, ws.log_mean);
}

}  // namespace
}  // namespace implicit::filter
