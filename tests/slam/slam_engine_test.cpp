// Particle SLAM on the generic engine: a step where no particle can move leaves uniform weights
// (counted as degenerate), and under known association the maps of all particles keep the same
// landmark slots, so the next step can use the landmark that step created.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {
namespace {

// The unicycle, except that a negative speed gives a NaN process covariance: a model failure.
class FailsOnReverse {
 public:
  double dt() const { return model_.dt(); }
  FailsOnReverse with_dt(double dt) const {
    FailsOnReverse m;
    m.model_ = model_.with_dt(dt);
    return m;
  }
  Pose predict(const Pose& x, const Control& u) const { return model_.predict(x, u); }
  Mat<3> process_covariance(const Pose& x, const Control& u) const {
    if (u(0) < 0) return Mat<3>::Constant(std::numeric_limits<double>::quiet_NaN());
    return model_.process_covariance(x, u);
  }
  Mat<3> jacobian_state(const Pose& x, const Control& u) const {
    return model_.jacobian_state(x, u);
  }

 private:
  robot::UnicycleModel model_;
};

TEST(SlamOnTheEngine, AFailedStepKeepsTheLandmarkSlotsOfAllParticles) {
  for (SlamMethod method : {SlamMethod::kFastSlam1, SlamMethod::kFastSlam2, SlamMethod::kImplicit,
                            SlamMethod::kImplicitRb}) {
    SlamOptions o;
    o.method = method;
    o.association = Association::kKnown;
    o.particles = 20;
    o.model = robot::AnyMotionModel(FailsOnReverse{});
    auto filter = make_slam_filter(o, Pose::Zero());
    // Step 1: every particle fails while landmark 7 is seen for the first time.
    const std::vector<Observation> first = {{Measurement(5.0, 0.1), 7}};
    filter->step(1, Control(-1.0, 0.0), first);
    EXPECT_EQ(filter->stats().degenerate_steps, 1u) << to_string(method);
    EXPECT_EQ(filter->map().landmarks.size(), 1u) << to_string(method);
    // Step 2: landmark 7 again, from a normal move: every particle, whichever was drawn, has it.
    const std::vector<Observation> second = {{Measurement(4.9, 0.1), 7}};
    ASSERT_NO_THROW(filter->step(2, Control(0.5, 0.0), second)) << to_string(method);
    EXPECT_EQ(filter->stats().degenerate_steps, 1u) << to_string(method);
    EXPECT_EQ(filter->stats().updates, 1u) << to_string(method);
    const MapEstimate map = filter->map();
    ASSERT_EQ(map.ids, std::vector<int>{7}) << to_string(method);
    EXPECT_TRUE(map.landmarks[0].allFinite()) << to_string(method);
  }
}

}  // namespace
}  // namespace implicit::slam
