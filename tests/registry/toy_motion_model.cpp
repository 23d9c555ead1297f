// A motion model the tool does not ship, added the way a user adds one: this file, linked into
// the `implicit` tool (tests/CMakeLists.txt builds it as `implicit-toy`), is all it takes for
// `implicit-toy simulate --model toy`, `mcl` and `slam` to run it (docs/design.md, "A new motion
// model"). The toy is the unicycle written again from its equations, so a run of it must give
// the numbers of the built-in unicycle (tests/registry/toy_model_check.py compares them).
#include <cmath>

#include "experiments/motion_models.hpp"

namespace {

using implicit::Vec;
using implicit::robot::Control;
using implicit::robot::Mat3;
using implicit::robot::Pose;

class ToyModel {
 public:
  ToyModel(double dt, Vec<2> control_sd, Vec<3> state_sd)
      : dt_(dt), control_sd_(control_sd), state_sd_(state_sd) {}
  double dt() const { return dt_; }
  ToyModel with_dt(double dt) const { return {dt, control_sd_, state_sd_}; }
  /// x + dt (v cos theta, v sin theta, omega)
  Pose predict(const Pose& x, const Control& u) const {
    return x + dt_ * Pose(u(0) * std::cos(x(2)), u(0) * std::sin(x(2)), u(1));
  }
  Mat3 jacobian_state(const Pose& x, const Control& u) const {
    Mat3 j = Mat3::Identity();
    j(0, 2) = -dt_ * u(0) * std::sin(x(2));
    j(1, 2) = dt_ * u(0) * std::cos(x(2));
    return j;
  }
  /// dt (dR/du P P^T dR/du^T + Q Q^T), the noise entering through v and omega.
  Mat3 process_covariance(const Pose& x, const Control& /*u*/) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const double v2 = control_sd_(0) * control_sd_(0);
    Mat3 sigma;
    sigma << v2 * c * c, v2 * c * s, 0.0, v2 * c * s, v2 * s * s, 0.0, 0.0, 0.0,
        control_sd_(1) * control_sd_(1);
    sigma.diagonal() += state_sd_.cwiseAbs2();
    return dt_ * sigma;
  }

 private:
  double dt_;
  Vec<2> control_sd_;
  Vec<3> state_sd_;
};

implicit::experiments::MotionModelEntry toy_entry() {
  implicit::experiments::MotionModelEntry e;
  e.name = "toy";
  e.description = "the unicycle, written again as a user's model";
  e.controls = "u1 = v [m/s], u2 = omega [rad/s]";
  e.keys = {{"dt", "control period [s]", 0.1}};
  e.default_noise = {{0.1, 0.05}, {0.02, 0.02, 0.2 * implicit::kPi / 180}};
  // make_motion_model hands over every key and both noise vectors: only unknown keys are left
  // to refuse.
  e.build = [](const implicit::robot::VehicleDeclaration& v,
               const implicit::experiments::MotionNoise& noise) {
    for (const auto& parameter : v.parameters)
      implicit::require(parameter.first == "dt",
                        "vehicle 'toy': expected parameters among dt, got '{}'", parameter.first);
    const auto& c = noise.control_sd;
    const auto& q = noise.state_sd;
    return implicit::robot::AnyMotionModel(
        ToyModel(*v.parameter("dt"), Vec<2>(c[0], c[1]), Vec<3>(q[0], q[1], q[2])));
  };
  return e;  // route_driver left empty: the unicycle's square route, at route_speed 1 m/s
}

const implicit::experiments::MotionModelRegistration toy{toy_entry()};

}  // namespace
