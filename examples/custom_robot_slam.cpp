// SLAM with your own robot: a differential drive written here (wheel speeds as the control), a
// synthetic log simulated from it, and every SLAM estimator run on it through
// SlamOptions::model. Nothing in the SLAM filters is specific to the paper's car: the robot only
// implements the motion-model concept with with_dt() (steps of any length) and jacobian_state()
// (EKF-SLAM linearises the motion).
//
//   build/examples/example_custom_robot_slam          # prints the pose and map error per method
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/simulate.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"

using namespace implicit;
using robot::Control;
using robot::Mat3;
using robot::Pose;

// Control u = (left wheel speed, right wheel speed) [m/s], wheels `track` metres apart:
//   v = (l + r) / 2, omega = (r - l) / track,  x_n = x + dt (v cos h, v sin h, omega) + w,
//   w ~ N(0, dt (J S J^T + Q Q^T)), J = d rate / d(l, r), S = diag(wheel_sd^2, wheel_sd^2).
class DifferentialDrive {
 public:
  explicit DifferentialDrive(double dt = 0.1) : dt_(dt) {}
  double dt() const { return dt_; }
  DifferentialDrive with_dt(double dt) const { return DifferentialDrive(dt); }

  Pose predict(const Pose& x, const Control& u) const {
    const double v = 0.5 * (u(0) + u(1)), omega = (u(1) - u(0)) / kTrack;
    return x + dt_ * Pose(v * std::cos(x(2)), v * std::sin(x(2)), omega);
  }
  Mat3 jacobian_state(const Pose& x, const Control& u) const {
    const double v = 0.5 * (u(0) + u(1));
    Mat3 j = Mat3::Identity();
    j(0, 2) = -dt_ * v * std::sin(x(2));
    j(1, 2) = dt_ * v * std::cos(x(2));
    return j;
  }
  Mat3 process_covariance(const Pose& x, const Control& /*u*/) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    Eigen::Matrix<double, 3, 2> j;  // d rate / d(l, r)
    j << 0.5 * c, 0.5 * c, 0.5 * s, 0.5 * s, -1.0 / kTrack, 1.0 / kTrack;
    Mat3 sigma = kWheelSd * kWheelSd * j * j.transpose();
    sigma.diagonal() += Vec<3>(0.02, 0.02, 0.004).cwiseAbs2();
    return dt_ * sigma;
  }

 private:
  static constexpr double kTrack = 0.5;     // [m]
  static constexpr double kWheelSd = 0.05;  // [m/s]
  double dt_;
};
static_assert(robot::LinearizableMotionModel<DifferentialDrive>);

int main() {
  // A log of this robot: the route driver gives (v, omega); convert to wheel speeds.
  const DifferentialDrive robot_model;
  const robot::Driver unicycle = robot::square_route_driver(1.0, 40.0, true);
  const robot::Driver wheels = [&](const Pose& x, double dt) {
    const Control vw = unicycle(x, dt);
    return Control(vw(0) - 0.25 * vw(1), vw(0) + 0.25 * vw(1));  // track / 2 = 0.25 m
  };
  robot::RobotLog log = robot::simulate_robot_log(robot_model, robot::RangeBearingSensor(), wheels,
                                                  robot::SimulationOptions{}, 7);
  log.vehicle = robot::VehicleDeclaration{"differential-drive", {{"dt", robot_model.dt()}}};
  const auto file = std::filesystem::temp_directory_path() / "example_custom_robot_slam.log";
  robot::write_robot_log(file, log);
  const slam::SlamDataset data = slam::read_slam_log(file);  // step lengths from the time stamps
  std::filesystem::remove(file);

  std::printf("%zu steps, %zu detections, vehicle '%s'\n", data.steps(), data.observation_count(),
              data.vehicle_model.c_str());
  for (slam::SlamMethod m :
       {slam::SlamMethod::kEkf, slam::SlamMethod::kFastSlam1, slam::SlamMethod::kFastSlam2,
        slam::SlamMethod::kImplicit, slam::SlamMethod::kImplicitRb}) {
    slam::SlamOptions options;
    options.method = m;
    options.particles = 50;
    options.model = robot_model;  // any LinearizableMotionModel
    const slam::SlamRun run = slam::run_filter(data, options);
    const slam::SlamMetrics metrics = slam::evaluate(data, run);
    std::printf("%-12s pose RMSE after alignment %.3f m, map shape %.3f m, %zu landmarks\n",
                std::string(slam::to_string(m)).c_str(), metrics.rmse_pose_aligned_m,
                metrics.map_shape_m, metrics.landmarks);
  }
}
