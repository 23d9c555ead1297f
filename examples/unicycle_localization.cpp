// A custom robot localized with the library: a unicycle (not the paper's car) with a
// range-bearing sensor among four known landmarks, tracked by standard (bootstrap) and implicit
// Monte Carlo localization on the same engine.
//
// All a new robot needs is a class satisfying implicit::robot::MotionModel: predict() (the mean
// of the next state), process_covariance() (symmetric positive definite) and dt(). The filter,
// both proposals and the weights stay untouched. Here the sensor is the library's
// RangeBearingSensor (bearing 0 = to the right of the robot, π/2 = straight ahead).
//
// The motion noise is large and the sensor accurate, the regime where the implicit proposal
// (which moves each particle towards what the data say before weighting it) needs far fewer
// particles than the bootstrap proposal (which moves particles blindly, then weights them).
#include <cmath>
#include <cstdio>
#include <vector>

#include "implicit/core/rng.hpp"
#include "implicit/filter/particle_filter.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/range_bearing.hpp"

namespace {

using implicit::robot::Control;  // (forward speed v [m/s], turn rate omega [rad/s]) for this robot
using implicit::robot::Mat3;
using implicit::robot::Pose;  // (x [m], y [m], heading [rad])

/// x' = x + v cos(θ) dt, y' = y + v sin(θ) dt, θ' = θ + ω dt, plus Gaussian noise.
struct Unicycle {
  double step = 0.1;                            // [s]
  Eigen::Vector3d noise_std{0.15, 0.15, 0.05};  // per step [m, m, rad]

  double dt() const { return step; }
  Pose predict(const Pose& x, const Control& u) const {
    return Pose(x(0) + u(0) * std::cos(x(2)) * step, x(1) + u(0) * std::sin(x(2)) * step,
                x(2) + u(1) * step);
  }
  Mat3 process_covariance(const Pose&, const Control&) const {
    return noise_std.array().square().matrix().asDiagonal();
  }
};
static_assert(implicit::robot::MotionModel<Unicycle>);

struct Result {
  double rmse = 0.0;
  double ess = 0.0;
};

template <typename Proposal>
Result localize(const std::vector<Control>& controls,
                const std::vector<std::vector<implicit::filter::LabelledMeasurement>>& scans,
                const std::vector<Pose>& truth, const implicit::robot::LandmarkMap& map,
                std::size_t particles) {
  implicit::filter::FilterOptions options;
  options.particles = particles;
  options.seed = 7;
  implicit::filter::ParticleFilter pf(Unicycle{}, implicit::robot::RangeBearingSensor(0.01, 1e-4),
                                      map, Proposal{}, options);
  pf.initialize(truth[0], Mat3(Eigen::Vector3d(0.1, 0.1, 0.01).asDiagonal()));
  Result r;
  int updates = 0;
  for (std::size_t n = 0; n < controls.size(); ++n) {
    const auto& s = pf.step(controls[n], scans[n]);
    const Pose& x = truth[n + 1];
    r.rmse += std::pow(s.mean(0) - x(0), 2) + std::pow(s.mean(1) - x(1), 2);
    if (s.updated) {
      r.ess += s.ess / static_cast<double>(particles);
      ++updates;
    }
  }
  r.rmse = std::sqrt(r.rmse / static_cast<double>(controls.size()));
  r.ess /= std::max(updates, 1);
  return r;
}

}  // namespace

int main() {
  implicit::robot::LandmarkMap map;
  map.add(0, implicit::robot::Landmark(10.0, 0.0));
  map.add(1, implicit::robot::Landmark(0.0, 10.0));
  map.add(2, implicit::robot::Landmark(-10.0, 0.0));
  map.add(3, implicit::robot::Landmark(0.0, -10.0));
  const implicit::robot::RangeBearingSensor sensor(0.01, 1e-4);  // variances: 0.1 m, 0.57°
  const Unicycle robot;

  // Simulate the truth (a circle of radius ≈ 5 m) and a scan of every landmark every 5 steps,
  // drawing the noise from streams of its own purpose so that the filters never reuse it.
  const int steps = 400;
  std::vector<Control> controls(steps, Control(1.0, 0.2));
  std::vector<Pose> truth{Pose(0.0, -5.0, 0.0)};
  std::vector<std::vector<implicit::filter::LabelledMeasurement>> scans(steps);
  const Eigen::Matrix3d chol = robot.process_covariance(truth[0], controls[0]).llt().matrixL();
  for (int n = 0; n < steps; ++n) {
    implicit::Rng rng(
        {.seed = 1, .step = static_cast<std::uint64_t>(n), .purpose = implicit::purpose::kUser});
    truth.push_back(robot.predict(truth.back(), controls[n]) + chol * rng.normal_vector<3>(3));
    if (n % 5 != 4) continue;
    for (int k = 0; k < static_cast<int>(map.positions().size()); ++k) {
      implicit::robot::Measurement z = sensor.predict(truth.back(), map.positions()[k]);
      z(0) += 0.1 * rng.normal();
      z(1) += 0.01 * rng.normal();
      scans[n].push_back({z, k});  // landmark known (index into the map); -1 would associate
    }
  }

  std::printf("%10s  %22s  %22s\n", "particles", "bootstrap RMSE / ESS/M", "implicit RMSE / ESS/M");
  for (std::size_t m : {10, 30, 100, 300}) {
    const auto b = localize<implicit::filter::BootstrapProposal>(controls, scans, truth, map, m);
    const auto i = localize<implicit::filter::ImplicitProposal>(controls, scans, truth, map, m);
    std::printf("%10zu  %13.3f m / %.2f  %13.3f m / %.2f\n", m, b.rmse, b.ess, i.rmse, i.ess);
  }
  return 0;
}
