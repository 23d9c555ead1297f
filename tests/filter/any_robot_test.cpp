// The engine with a robot other than the Ute: a unicycle on a simulated log, steps of the log's
// own lengths, and detections named by landmark ids.
#include <gtest/gtest.h>

#include <cmath>

#include "implicit/core/error.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/simulate.hpp"

namespace implicit::filter {
namespace {

// With no detections the weights stay equal, so the filter's mean after one step is the sample
// mean of M draws from N(f(x0, u; dt), Sigma1(dt)): its error has standard error
// sqrt(Sigma1_00 / M). A step of 0.37 s must move the mean by v * 0.37, not by v * dt().
TEST(AnyRobot, EachStepTakesItsOwnLength) {
  const robot::UnicycleModel model;  // dt() = 0.1
  FilterOptions options;
  options.particles = 4000;
  options.seed = 3;
  robot::LandmarkMap map;
  map.add(5, Landmark(10, 10));
  ParticleFilter pf(model, robot::RangeBearingSensor(), map, BootstrapProposal{}, options);
  pf.initialize(Pose::Zero(), 1e-12 * Mat3::Identity());
  const double dt = 0.37, v = 2.0;
  pf.set_step_length(dt);
  const StepSummary& s = pf.step(Control(v, 0.0));
  const Mat3 sigma1 = model.with_dt(dt).process_covariance(Pose::Zero(), Control(v, 0.0));
  const double se = std::sqrt(sigma1(0, 0) / static_cast<double>(options.particles));
  EXPECT_NEAR(s.mean(0), v * dt, 5 * se);
  EXPECT_GT(std::abs(s.mean(0) - v * model.dt()), 20 * se);  // the nominal step is far off
}

robot::RobotLog unicycle_log(std::uint64_t seed) {
  robot::SimulationOptions o;
  o.steps = 900;
  const robot::UnicycleModel model;
  robot::RobotLog log =
      robot::simulate_robot_log(model, robot::RangeBearingSensor(),
                                robot::square_route_driver(1.0, o.route_side, true), o, seed);
  log.vehicle = robot::declare_vehicle(model.params());
  return log;
}

// Implicit MCL with the model the data were simulated from tracks the truth. The bound is a
// sanity bound, not a fitted number: with 3-8 labelled detections of range sd 0.22 m per scan
// the posterior position sd is about 0.1 m, while dead reckoning drifts by metres.
TEST(AnyRobot, ImplicitMclTracksASimulatedUnicycle) {
  const robot::RobotLog log = unicycle_log(4);
  const robot::UnicycleModel model;
  const LocalizationProblem problem = make_problem(log, model.dt());
  FilterOptions options;
  options.particles = 100;
  const LocalizationRun run =
      run_localization(problem, model, robot::RangeBearingSensor(), ImplicitProposal{}, options);
  const LocalizationMetrics m = localization_metrics(run, problem.truth, options.particles);
  std::vector<Pose> dr;
  Pose x = problem.initial_mean;
  for (std::size_t n = 0; n < problem.schedule.steps.size(); ++n)
    dr.push_back(x = model.with_dt(problem.step_dt[n]).predict(x, problem.schedule.steps[n].u));
  double dr_sq = 0;
  for (std::size_t n = 0; n < dr.size(); ++n)
    dr_sq += (dr[n].head<2>() - problem.truth.position[n]).squaredNorm();
  EXPECT_LT(m.rmse, 0.5);
  EXPECT_GT(std::sqrt(dr_sq / static_cast<double>(dr.size())), 4 * m.rmse);
  EXPECT_EQ(m.failures, 0);
}

TEST(AnyRobot, AnUnknownLandmarkIdIsAnErrorNamingIt) {
  robot::RobotLog log = unicycle_log(6);
  log.scans[3].observations.push_back({Measurement(3.0, 1.0), 99999});
  try {
    make_problem(log, 0.1);
    ADD_FAILURE() << "an unknown landmark id was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("99999"), std::string::npos) << e.what();
  }
}

TEST(AnyRobot, StepLengthsComeFromTheTimeStamps) {
  const robot::RobotLog log = unicycle_log(7);
  const LocalizationProblem p = make_problem(log, 0.1);
  ASSERT_EQ(p.step_dt.size(), log.controls.size());
  EXPECT_DOUBLE_EQ(p.step_dt[0], log.controls[0].time - log.initial->time);
  for (std::size_t n = 1; n < p.step_dt.size(); ++n)
    EXPECT_NEAR(p.step_dt[n], log.controls[n].time - log.controls[n - 1].time, 1e-12);
}

}  // namespace
}  // namespace implicit::filter
