// A custom robot localized with the library's filter: a unicycle (state x, y, heading; control
// speed v and turn rate omega) with a range-bearing sensor, on a small synthetic map. Nothing in
// the filter is specific to the paper's vehicle: the unicycle only implements the MotionModel
// concept (implicit/robot/models.hpp) and both proposals run on it unchanged.
#include <cmath>
#include <cstdio>
#include <vector>

#include "implicit/filter/particle_filter.hpp"

using namespace implicit;
using robot::Control;
using robot::Landmark;
using robot::Mat3;
using robot::Pose;

// x_n = x_{n-1} + dt (v cos h, v sin h, omega) + w,  w ~ N(0, dt (J P P^T J^T + Q Q^T)),
// J = d rate / d(v, omega): speed and turn-rate noise mapped into the state, plus a small state
// noise so that the covariance is positive definite (the implicit proposal needs its Cholesky).
class Unicycle {
 public:
  double dt() const { return 0.1; }
  Pose predict(const Pose& x, const Control& u) const {
    return x + dt() * Pose(u(0) * std::cos(x(2)), u(0) * std::sin(x(2)), u(1));
  }
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    Eigen::Matrix<double, 3, 2> j;
    j << std::cos(x(2)), 0.0, std::sin(x(2)), 0.0, 0.0, 1.0;
    (void)u;
    const Vec<2> p(0.3, 0.1);           // std of speed [m/s] and turn rate [rad/s]
    const Vec<3> q(0.02, 0.02, 0.005);  // state noise std
    Mat3 s = j * p.cwiseAbs2().asDiagonal() * j.transpose();
    s.diagonal() += q.cwiseAbs2();
    return dt() * s;
  }
};
static_assert(robot::MotionModel<Unicycle>);

template <typename Proposal>
double run(const Unicycle& model, const robot::LandmarkMap& map, const std::vector<Control>& u,
           const std::vector<std::vector<filter::LabelledMeasurement>>& z,
           const std::vector<Pose>& truth, const char* name) {
  filter::FilterOptions options;
  options.particles = 200;
  options.seed = 42;
  filter::ParticleFilter pf(model, robot::RangeBearingSensor(), map, Proposal{}, options);
  pf.initialize(Pose(0, 0, 0), Vec<3>(0.2, 0.2, 0.05).cwiseAbs2().asDiagonal().toDenseMatrix());
  double se = 0.0, ess = 0.0;
  int updates = 0;
  for (std::size_t n = 0; n < u.size(); ++n) {
    const filter::StepSummary& s = pf.step(u[n], z[n]);
    se += (s.mean.head<2>() - truth[n].head<2>()).squaredNorm();
    if (s.updated) {
      ess += s.ess / static_cast<double>(options.particles);
      ++updates;
    }
  }
  const double rmse = std::sqrt(se / static_cast<double>(u.size()));
  std::printf("%-9s position RMSE %.3f m, mean ESS/M at updates %.2f\n", name, rmse, ess / updates);
  return rmse;
}

int main() {
  const Unicycle model;
  const robot::RangeBearingSensor sensor;  // Sigma2 = diag(0.05 m^2, 8.7e-4 rad^2)
  robot::LandmarkMap map;
  for (int k = 0; k < 10; ++k)
    map.add(k, Landmark(12.0 * std::cos(0.63 * k) + 2.0, 12.0 * std::sin(0.63 * k) + 9.0));

  // Simulate: drive a circle, observe landmarks within 15 m ahead every 5th step (unlabelled).
  std::vector<Control> u;
  std::vector<Pose> truth;
  std::vector<std::vector<filter::LabelledMeasurement>> z;
  Pose x(0, 0, 0);
  const Mat<2> l2 = sensor.noise_covariance().llt().matrixL();
  for (int n = 1; n <= 400; ++n) {
    const Control c(2.0, 0.2);
    Rng rng({7, static_cast<std::uint64_t>(n), 0, purpose::kData});
    const Mat3 l1 = model.process_covariance(x, c).llt().matrixL();
    // One call for the three draws: the order of function arguments is unspecified, so
    // Vec<3>(rng.normal(), rng.normal(), rng.normal()) differs between compilers.
    x = model.predict(x, c) + l1 * rng.normal_vector<3>();
    std::vector<filter::LabelledMeasurement> obs;
    if (n % 5 == 0)
      for (std::size_t k = 0; k < map.size(); ++k) {
        const robot::Measurement h = sensor.predict(x, map.position(k));
        const double b = wrap_angle(h(1));
        if (h(0) < 15.0 && b > 0.0 && b < kPi) obs.push_back({h + l2 * rng.normal_vector<2>(), -1});
      }
    u.push_back(c);
    truth.push_back(x);
    z.push_back(obs);
  }
  std::printf("unicycle, 400 steps, 200 particles, unlabelled range-bearing detections\n");
  run<filter::BootstrapProposal>(model, map, u, z, truth, "standard");
  run<filter::ImplicitProposal>(model, map, u, z, truth, "implicit");
  return 0;
}
