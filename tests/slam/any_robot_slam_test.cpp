// SLAM with a robot other than the Ute: every method on a simulated unicycle log (irregular
// step lengths, detections labelled by id), through SlamOptions::model.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <unistd.h>

#include "implicit/robot/simulate.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {
namespace {

SlamDataset unicycle_dataset(std::uint64_t seed) {
  robot::SimulationOptions o;
  o.steps = 900;
  const robot::UnicycleModel model;
  robot::RobotLog log =
      robot::simulate_robot_log(model, robot::RangeBearingSensor(),
                                robot::square_route_driver(1.0, o.route_side, true), o, seed);
  log.vehicle = robot::declare_vehicle(model.params());
  // One file per process and seed: the tests of this file (and other checkouts) run in parallel.
  const auto file = std::filesystem::temp_directory_path() /
                    ("implicit_any_robot_slam_" + std::to_string(::getpid()) + "_" +
                     std::to_string(seed) + ".log.gz");
  robot::write_robot_log(file, log);
  SlamDataset d = read_slam_log(file);
  std::filesystem::remove(file);
  return d;
}

TEST(AnyRobotSlam, ReadsTheDeclaredVehicleAndTheStepLengths) {
  const SlamDataset d = unicycle_dataset(2);
  EXPECT_EQ(d.vehicle_model, "unicycle");
  EXPECT_EQ(d.vehicle.dt, robot::UnicycleParams{}.dt);
  ASSERT_EQ(d.step_dt.size(), d.steps());
  double shortest = 1e9, longest = 0;
  for (double t : d.step_dt) {
    shortest = std::min(shortest, t);
    longest = std::max(longest, t);
  }
  EXPECT_GT(longest - shortest, 0.5 * d.vehicle.dt);
}

// Every method with the unicycle model tracks the robot and maps the landmarks it saw. Sanity
// bounds, not fitted numbers: detections have range sd 0.22 m, and dead reckoning alone drifts by
// over a metre RMS over the run (checked below), so a filter that ignored the model or the step
// lengths would not stay within them.
TEST(AnyRobotSlam, EveryMethodRunsTheUnicycle) {
  const SlamDataset d = unicycle_dataset(3);
  const robot::UnicycleModel model;
  Pose x = d.initial_pose;
  double dr_sq = 0.0;
  for (std::size_t n = 1; n <= d.steps(); ++n) {
    x = model.with_dt(d.step_length(n)).predict(x, d.control(n));
    dr_sq += (x.head<2>() - d.truth[n].head<2>()).squaredNorm();
  }
  const double dead_reckoning = std::sqrt(dr_sq / static_cast<double>(d.steps()));
  EXPECT_GT(dead_reckoning, 1.0);  // the data make the model matter
  for (SlamMethod m : {SlamMethod::kEkf, SlamMethod::kFastSlam1, SlamMethod::kFastSlam2,
                       SlamMethod::kImplicit, SlamMethod::kImplicitRb}) {
    SlamOptions opt;
    opt.method = m;
    opt.particles = 50;
    opt.model = model;
    const SlamRun run = run_filter(d, opt);
    const SlamMetrics met = evaluate(d, run);
    EXPECT_LT(met.rmse_pose_aligned_m, 1.0) << to_string(m);
    EXPECT_LT(met.map_shape_m, 1.0) << to_string(m);
    EXPECT_LT(met.rmse_pose_aligned_m, 0.5 * dead_reckoning) << to_string(m);
  }
}

TEST(AnyRobotSlam, AFixedStepLengthIsTheModelsOwn) {
  // AnyMotionModel keeps the model's answers: the Ute through it equals the Ute.
  const robot::UteModel ute;
  const robot::AnyMotionModel any = ute;
  const Pose x(1.0, 2.0, 0.3);
  const Control u(2.0, 0.1);
  EXPECT_EQ(any.predict(x, u), ute.predict(x, u));
  EXPECT_EQ(any.process_covariance(x, u), ute.process_covariance(x, u));
  EXPECT_EQ(any.jacobian_state(x, u), ute.jacobian_state(x, u));
  EXPECT_EQ(any.with_dt(0.05).predict(x, u), ute.with_dt(0.05).predict(x, u));
}

}  // namespace
}  // namespace implicit::slam
