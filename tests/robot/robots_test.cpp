// Any robot: the unicycle model, the mounted range-bearing sensor (derivatives against automatic
// differentiation and finite differences), the `vehicle` record and simulated logs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/core/jet.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/simulate.hpp"

namespace implicit::robot {
namespace {

Pose random_pose(Rng& rng) {
  // One draw per declarator: the order of function arguments is unspecified.
  const double x = 10 * rng.uniform() - 5, y = 10 * rng.uniform() - 5;
  return Pose(x, y, 8 * rng.uniform() - 4);
}

TEST(Unicycle, JacobianMatchesAutomaticDifferentiation) {
  const UnicycleModel model({.dt = 0.37});
  Rng rng({11, 0, 0, purpose::kUser});
  for (int trial = 0; trial < 20; ++trial) {
    const Pose x = random_pose(rng);
    const double speed = 4 * rng.uniform() - 2;
    const Control u(speed, 2 * rng.uniform() - 1);
    const Mat3 j = model.jacobian_state(x, u);
    for (int row = 0; row < 3; ++row) {
      auto component = [&](const auto& xj) {
        using std::cos, std::sin;
        const double dt = model.dt();
        const auto next = row == 0   ? xj(0) + dt * u(0) * cos(xj(2))
                          : row == 1 ? xj(1) + dt * u(0) * sin(xj(2))
                                     : xj(2) + dt * u(1);
        return next;
      };
      const auto [value, grad, hess] = autodiff_hessian<3>(component, x);
      EXPECT_NEAR(value, model.predict(x, u)(row), 1e-12);
      for (int col = 0; col < 3; ++col) EXPECT_NEAR(j(row, col), grad(col), 1e-12);
    }
  }
}

TEST(Unicycle, TurnsOnTheSpotAndTakesItsOwnStepLength) {
  const UnicycleModel model;
  const Pose x(1.0, 2.0, 0.3);
  const Pose spun = model.with_dt(0.5).predict(x, Control(0.0, 0.8));
  EXPECT_DOUBLE_EQ(spun(0), 1.0);
  EXPECT_DOUBLE_EQ(spun(1), 2.0);
  EXPECT_DOUBLE_EQ(spun(2), 0.3 + 0.5 * 0.8);
  // Standing still, Sigma1 is still positive definite (the state noise), and scales with dt.
  const Mat3 s1 = model.process_covariance(x, Control(0.0, 0.0));
  EXPECT_EQ(Eigen::LLT<Mat3>(s1).info(), Eigen::Success);
  const Mat3 s2 = model.with_dt(2 * model.dt()).process_covariance(x, Control(0.0, 0.0));
  EXPECT_LT((s2 - 2 * s1).norm(), 1e-15);
}

TEST(MountedSensor, JacobianMatchesAutomaticDifferentiation) {
  Rng rng({12, 0, 0, purpose::kUser});
  for (int trial = 0; trial < 50; ++trial) {
    const SensorMounting mount{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 4 * rng.uniform() - 2};
    const MountedRangeBearingSensor s(mount);
    const Pose x = random_pose(rng);
    const double mx = x(0) + 3 + 5 * rng.uniform();
    const Landmark m(mx, x(1) - 4 + 8 * rng.uniform());
    Measurement h;
    Mat23 j;
    s.predict_with_jacobian(x, m, h, j);
    for (int row = 0; row < 2; ++row) {
      const auto [value, grad, hess] =
          autodiff_hessian<3>([&](const auto& xj) { return s.measure(xj, m)(row); }, x);
      EXPECT_NEAR(h(row), value, 1e-12);
      for (int col = 0; col < 3; ++col) EXPECT_NEAR(j(row, col), grad(col), 1e-10) << row << col;
    }
  }
}

// The Hessian (automatic) against central differences of the written-out Jacobian: two
// independent routes to the same second derivatives.
TEST(MountedSensor, HessianMatchesFiniteDifferencesOfTheJacobian) {
  const MountedRangeBearingSensor s({0.4, -0.25, 0.0});
  const Pose x(0.5, -1.0, 0.7);
  const Landmark m(6.0, 2.0);
  Mat3 hr, hb;
  s.hessian_pose(x, m, hr, hb);
  const double step = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Pose xp = x, xm = x;
    xp(k) += step;
    xm(k) -= step;
    const Mat23 d = (s.jacobian_pose(xp, m) - s.jacobian_pose(xm, m)) / (2 * step);
    for (int col = 0; col < 3; ++col) {
      EXPECT_NEAR(hr(col, k), d(0, col), 1e-7);
      EXPECT_NEAR(hb(col, k), d(1, col), 1e-7);
    }
  }
}

TEST(MountedSensor, AtTheStateWithTheSickConventionItIsTheUtesLaser) {
  const MountedRangeBearingSensor mounted;
  const RangeBearingSensor laser;
  Rng rng({13, 0, 0, purpose::kUser});
  for (int trial = 0; trial < 20; ++trial) {
    const Pose x = random_pose(rng);
    const double mx = 10 * rng.uniform() - 5;
    const Landmark m(mx, 10 * rng.uniform() - 5);
    const Measurement a = mounted.predict(x, m), b = laser.predict(x, m);
    EXPECT_NEAR(a(0), b(0), 1e-12);
    EXPECT_NEAR(wrap_angle(a(1) - b(1)), 0.0, 1e-12);
    EXPECT_LT((mounted.jacobian_pose(x, m) - laser.jacobian_pose(x, m)).norm(), 1e-12);
    Mat3 h0, h1, g0, g1;
    mounted.hessian_pose(x, m, h0, h1);
    laser.hessian_pose(x, m, g0, g1);
    EXPECT_LT((h0 - g0).norm() + (h1 - g1).norm(), 1e-10);
    EXPECT_LT((laser.inverse(x, b) - m).norm(), 1e-9);
  }
}

TEST(MountedSensor, InverseFindsTheLandmarkForAnyMounting) {
  const MountedRangeBearingSensor s({0.3, 0.1, 0.0});  // 0 = straight ahead
  const Pose x(1.0, 1.0, 0.5);
  const Landmark m(4.0, 3.0);
  EXPECT_LT((s.inverse(x, s.predict(x, m)) - m).norm(), 1e-12);
  // Straight ahead of the sensor reads bearing 0 in this convention.
  const Landmark ahead = s.inverse(x, Measurement(5.0, 0.0));
  EXPECT_NEAR(s.predict(x, ahead)(1), 0.0, 1e-12);
}

TEST(VehicleRecord, RoundTripsAndRejectsBadInputWithLineAndField) {
  RobotLog log;
  log.vehicle = declare_vehicle(UteParams{});
  log.landmarks.add(4, Landmark(1, 2));
  std::ostringstream out;
  write_robot_log(out, log);
  std::istringstream in(out.str());
  const RobotLog back = parse_robot_log(in, "v.log");
  ASSERT_TRUE(back.vehicle);
  EXPECT_EQ(back.vehicle->model, "ute");
  EXPECT_EQ(*back.vehicle->parameter("L"), UteParams{}.wheelbase);
  EXPECT_FALSE(back.vehicle->parameter("nonsense"));
  auto fails = [](const std::string& text, const std::string& expected) {
    std::istringstream bad(text);
    try {
      parse_robot_log(bad, "bad.log");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  fails("vehicle\n", "bad.log:1: record 'vehicle'");
  fails("vehicle unicycle dt=0.1\nvehicle ute\n", "bad.log:2: expected one 'vehicle' record");
  fails("vehicle unicycle dt=fast\n", "bad.log:1: field 'dt': expected a finite number");
  fails("vehicle unicycle dt=0.1 dt=0.2\n", "field 'dt': expected each key once");
  fails("vehicle unicycle 0.1\n", "bad.log:1: field 2: expected key=value, got '0.1'");
}

TEST(Simulate, WritesALogThatReadsBackWithIdsAndIrregularTimes) {
  SimulationOptions o;
  o.steps = 1200;
  const UnicycleModel model;
  RobotLog log = simulate_robot_log(model, RangeBearingSensor(),
                                    square_route_driver(1.0, o.route_side, true), o, 5);
  log.vehicle = declare_vehicle(model.params());
  const auto file = std::filesystem::temp_directory_path() / "implicit_robots_test.log.gz";
  write_robot_log(file, log);
  const RobotLog back = read_robot_log(file);
  std::filesystem::remove(file);
  ASSERT_EQ(back.controls.size(), 1200u);
  ASSERT_TRUE(back.vehicle);
  EXPECT_EQ(back.vehicle->model, "unicycle");
  double shortest = 1e9, longest = 0, previous = 0;
  int spins = 0;
  for (const TimedControl& c : back.controls) {
    shortest = std::min(shortest, c.time - previous);
    longest = std::max(longest, c.time - previous);
    previous = c.time;
    spins += c.u(0) == 0.0 && c.u(1) != 0.0 ? 1 : 0;
  }
  EXPECT_GE(shortest, 0.5 * model.dt() - 1e-12);
  EXPECT_LE(longest, 1.5 * model.dt() + 1e-12);
  EXPECT_GT(longest - shortest, 0.5 * model.dt());  // irregular
  EXPECT_GT(spins, 0);                              // the corners are turned on the spot
  int labelled = 0;
  for (const ObservationSet& s : back.scans)
    for (const Observation& ob : s.observations) {
      EXPECT_GE(back.landmarks.index_of(ob.landmark_id), 0);
      EXPECT_NE(back.landmarks.index_of(ob.landmark_id), ob.landmark_id);  // ids are not indices
      ++labelled;
    }
  EXPECT_GT(labelled, 100);
}

}  // namespace
}  // namespace implicit::robot
