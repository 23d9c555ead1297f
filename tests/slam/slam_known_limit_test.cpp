// Implicit SLAM's pose objective holds at most kMaxKnownPerStep known landmarks a step: a step
// that gives a particle more is refused with the step named (it used to weight every particle
// zero in silence), while a proposal without that bound takes it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/slam/proposals.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace {

namespace slam = implicit::slam;
using implicit::InvalidArgument;
using implicit::robot::Control;
using implicit::robot::Landmark;
using implicit::robot::Pose;

/// `count` landmarks on a circle of radius 5 m about the origin, and their exact detections from
/// the pose the filter predicts for one step of `u` from the origin (the filters' mean path).
struct CircleOfLandmarks {
  std::vector<Landmark> landmarks;
  std::vector<slam::Observation> detections;
};

CircleOfLandmarks circle_of_landmarks(int count, const slam::SlamOptions& opt, const Control& u) {
  CircleOfLandmarks c;
  const Pose x = implicit::robot::UteModel(opt.motion).predict(Pose::Zero(), u);
  for (int k = 0; k < count; ++k) {
    const double a = 2.0 * implicit::kPi * k / count;
    const Landmark m(5.0 * std::cos(a), 5.0 * std::sin(a));
    c.landmarks.push_back(m);
    c.detections.push_back({opt.sensor.predict(x, m), k});
  }
  return c;
}

std::string refusal(slam::SlamMethod method, int count) {
  slam::SlamOptions opt;
  opt.method = method;
  opt.particles = 4;
  const Control u(1.0, 0.0);
  const CircleOfLandmarks c = circle_of_landmarks(count, opt, u);
  auto filter = slam::make_slam_filter(opt, Pose::Zero());
  filter->set_known_map(c.landmarks);
  try {
    filter->step(1, u, c.detections);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  EXPECT_TRUE(std::isfinite(filter->pose().mean(0)));
  return {};
}

TEST(KnownLandmarkLimit, ImplicitSlamRefusesAStepBeyondItsCapacityNamingTheStep) {
  const int over = slam::kMaxKnownPerStep + 1;
  for (const slam::SlamMethod method :
       {slam::SlamMethod::kImplicit, slam::SlamMethod::kImplicitRb}) {
    const std::string message = refusal(method, over);
    EXPECT_NE(message.find("SLAM step 1"), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(over) + " known landmarks"), std::string::npos)
        << message;
    EXPECT_NE(message.find(std::to_string(slam::kMaxKnownPerStep)), std::string::npos) << message;
  }
}

TEST(KnownLandmarkLimit, AtTheLimitAndWithoutABoundTheStepRuns) {
  EXPECT_EQ(refusal(slam::SlamMethod::kImplicitRb, slam::kMaxKnownPerStep), "");
  EXPECT_EQ(refusal(slam::SlamMethod::kFastSlam2, slam::kMaxKnownPerStep + 1), "");
  EXPECT_EQ(refusal(slam::SlamMethod::kFastSlam1, slam::kMaxKnownPerStep + 1), "");
}

}  // namespace
