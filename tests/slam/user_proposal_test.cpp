// Pose proposals plug into particle SLAM from outside the library (LandmarkPoseProposal,
// make_particle_slam_filter): a user's FastSLAM 1.0 written from the definitions (motion-model
// draw, innovation-density weight) gives the built-in fastslam1's numbers bit for bit, and a
// user's wrapper of implicit SLAM (A) gives implicit's, through the optional members.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/mounted_sensor.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/pose_proposals.hpp"
#include "implicit/slam/slam_filter.hpp"
#include "slam/test_data.hpp"

namespace {

using implicit::Mat;
using implicit::Rng;
using implicit::Vec;
using implicit::robot::RangeBearingSensor;
namespace slam = implicit::slam;

// FastSLAM 1.0 (Montemerlo et al. 2002) as a user writes it, against the public step only:
// X ~ N(f, Sigma1), then for every known landmark the innovation density
// N(nu; 0, H_m P H_m^T + Sigma2) at X, in the log domain.
struct UserFastSlam1 {
  static constexpr std::uint64_t kPurpose = implicit::purpose::kProposal;
  slam::PoseDraw propose(const slam::PoseStep<>& s, Rng& rng) const {
    slam::PoseDraw d;
    d.x = s.f + s.sigma1_llt.matrixL() * rng.normal_vector<3>();
    for (const slam::KnownLandmark& k : s.known) {
      const Mat<2> hm = s.sensor.jacobian_landmark(d.x, k.mean);
      const Eigen::LLT<Mat<2>> llt(hm * k.cov * hm.transpose() + s.sensor.noise_covariance());
      if (llt.info() != Eigen::Success) {
        d.log_weight = -std::numeric_limits<double>::infinity();
        return d;
      }
      const Vec<2> nu = -RangeBearingSensor::residual(s.sensor.predict(d.x, k.mean), k.z);
      const Mat<2> l = llt.matrixL();
      d.log_weight +=
          -implicit::kLog2Pi - std::log(l(0, 0)) - std::log(l(1, 1)) - 0.5 * nu.dot(llt.solve(nu));
    }
    return d;
  }
};
static_assert(slam::LandmarkPoseProposal<UserFastSlam1>);
static_assert(!slam::PointLandmarkProposal<UserFastSlam1>);

// A user's decorator of implicit SLAM (A) that forwards what it is asked: with `joint` it also
// forwards the optional joint draw of a new landmark, without it the filter places new landmarks
// by inversion.
template <bool joint>
struct WrappedImplicitA {
  static constexpr std::uint64_t kPurpose = slam::ImplicitPoseProposal::kPurpose;
  slam::ImplicitPoseProposal inner{true};
  bool point_landmarks() const { return inner.point_landmarks(); }
  slam::PoseDraw propose(const slam::PoseStep<>& s, Rng& rng) const {
    return inner.propose(s, rng);
  }
  std::optional<slam::NewLandmarkDraw> propose_with_new_landmark(const slam::PoseStep<>& s,
                                                                 const slam::Measurement& z,
                                                                 Rng& rng) const requires joint {
    return inner.propose_with_new_landmark(s, z, rng);
  }
};
static_assert(slam::JointNewLandmarkProposal<WrappedImplicitA<true>>);
static_assert(!slam::JointNewLandmarkProposal<WrappedImplicitA<false>>);

slam::SlamDataset short_data(std::size_t steps, std::uint64_t seed) {
  slam::SlamScenario sc = slam::load_carpark_scenario(slam::repository_data_dir());
  sc.controls.resize(steps);
  return slam::generate_synthetic(sc, slam::SyntheticConfig(), seed);
}

// Runs both filters over the data and returns how many steps differed in any bit of the pose
// estimate, the map or the counters (0: bit-identical throughout).
int differing_steps(slam::SlamFilter& a, slam::SlamFilter& b, const slam::SlamDataset& d) {
  int differing = 0;
  for (std::size_t n = 1; n <= d.steps(); ++n) {
    a.set_step_length(d.step_length(n));
    b.set_step_length(d.step_length(n));
    a.step(n, d.control(n), d.observations(n));
    b.step(n, d.control(n), d.observations(n));
    const slam::MapEstimate ma = a.map(), mb = b.map();
    bool same = a.pose().mean == b.pose().mean && a.pose().cov == b.pose().cov &&
                ma.ids == mb.ids && ma.landmarks.size() == mb.landmarks.size();
    for (std::size_t k = 0; same && k < ma.landmarks.size(); ++k)
      same = ma.landmarks[k] == mb.landmarks[k];
    const slam::SlamStats &sa = a.stats(), &sb = b.stats();
    same = same && sa.updates == sb.updates && sa.new_landmarks == sb.new_landmarks &&
           sa.resamplings == sb.resamplings && sa.ess_fraction_sum == sb.ess_fraction_sum &&
           sa.newton_iterations == sb.newton_iterations &&
           sa.degenerate_steps == sb.degenerate_steps;
    if (!same) ++differing;
  }
  return differing;
}

slam::SlamOptions options(slam::SlamMethod method, slam::Association association) {
  slam::SlamOptions o;
  o.method = method;
  o.association = association;
  o.particles = 24;
  o.seed = 7;
  return o;
}

TEST(UserPoseProposal, FastSlam1WrittenByTheUserIsBitIdenticalToTheBuiltIn) {
  const slam::SlamDataset d = short_data(600, 3);
  for (auto association : {slam::Association::kKnown, slam::Association::kMaximumLikelihood}) {
    const slam::SlamOptions o = options(slam::SlamMethod::kFastSlam1, association);
    auto builtin = slam::make_slam_filter(o, d.initial_pose);
    auto user = slam::make_particle_slam_filter(o, d.initial_pose, UserFastSlam1{});
    EXPECT_EQ(differing_steps(*builtin, *user, d), 0) << slam::to_string(association);
    EXPECT_GT(user->stats().resamplings, 0u);  // the weights did something
    EXPECT_GT(user->stats().updates, 0u);
  }
}

// The comparison above sees a difference when there is one: the same user proposal with another
// seed, or the built-in FastSLAM 2.0, differs at (nearly) every step.
TEST(UserPoseProposal, TheBitComparisonDetectsADifferentFilter) {
  const slam::SlamDataset d = short_data(200, 3);
  slam::SlamOptions o = options(slam::SlamMethod::kFastSlam1, slam::Association::kKnown);
  auto builtin = slam::make_slam_filter(o, d.initial_pose);
  o.seed += 1;
  auto reseeded = slam::make_particle_slam_filter(o, d.initial_pose, UserFastSlam1{});
  EXPECT_GT(differing_steps(*builtin, *reseeded, d), 190);
  o.seed -= 1;
  auto first = slam::make_particle_slam_filter(o, d.initial_pose, UserFastSlam1{});
  auto second = slam::make_particle_slam_filter(o, d.initial_pose, slam::FastSlam2Proposal{});
  EXPECT_GT(differing_steps(*first, *second, d), 190);
}

// Implicit SLAM (A) reaches the filter through the optional members: point landmarks (no EKF
// update, zero covariance) and the joint draw of a new landmark. A wrapper forwarding both is
// implicit; one without the joint draw is a different filter (new landmarks by inversion).
TEST(UserPoseProposal, OptionalMembersReachTheFilter) {
  const slam::SlamDataset d = short_data(600, 4);
  for (auto association : {slam::Association::kKnown, slam::Association::kMaximumLikelihood}) {
    const slam::SlamOptions o = options(slam::SlamMethod::kImplicit, association);
    auto builtin = slam::make_slam_filter(o, d.initial_pose);
    auto wrapped = slam::make_particle_slam_filter(o, d.initial_pose, WrappedImplicitA<true>{});
    EXPECT_EQ(differing_steps(*builtin, *wrapped, d), 0) << slam::to_string(association);
    auto builtin2 = slam::make_slam_filter(o, d.initial_pose);
    auto no_joint = slam::make_particle_slam_filter(o, d.initial_pose, WrappedImplicitA<false>{});
    EXPECT_GT(differing_steps(*builtin2, *no_joint, d), 0) << slam::to_string(association);
  }
}

// The built-in proposals behind the front door: pose_proposal(options) is what make_slam_filter
// uses, for every particle method.
TEST(UserPoseProposal, TheFrontDoorIsTheBuiltInProposal) {
  const slam::SlamDataset d = short_data(300, 5);
  for (auto method : {slam::SlamMethod::kFastSlam1, slam::SlamMethod::kFastSlam2,
                      slam::SlamMethod::kImplicit, slam::SlamMethod::kImplicitRb}) {
    const slam::SlamOptions o = options(method, slam::Association::kMaximumLikelihood);
    auto a = slam::make_slam_filter(o, d.initial_pose);
    auto b = slam::make_particle_slam_filter(o, d.initial_pose, slam::pose_proposal(o));
    EXPECT_EQ(differing_steps(*a, *b, d), 0) << slam::to_string(method);
  }
}

// The built-ins read the sensor through robot::LandmarkSensor only: with the mounted sensor at
// zero offset (exactly RangeBearingSensor, robot/mounted_sensor.hpp) they draw the same poses
// and weights from the same stream, up to the round-off of its other formulas (sqrt for hypot,
// Hessians by automatic differentiation): 1e-9 where the draws are O(10) and Newton runs to
// round-off.
TEST(UserPoseProposal, TheBuiltInsReadTheSensorThroughTheSeam) {
  const RangeBearingSensor plain;
  const implicit::robot::MountedRangeBearingSensor mounted({}, plain.noise_covariance()(0, 0),
                                                           plain.noise_covariance()(1, 1));
  const slam::Pose f(10.0, 5.0, 0.3);
  Mat<3> sigma1;
  sigma1 << 4e-3, 1e-3, 0.0, 1e-3, 3e-3, 2e-4, 0.0, 2e-4, 1e-4;
  const Eigen::LLT<Mat<3>> llt(sigma1);
  std::vector<slam::KnownLandmark> known(2);
  known[0].mean = Vec<2>(20, 12);
  known[0].cov << 0.05, 0.01, 0.01, 0.03;
  known[1].mean = Vec<2>(11, 17);
  known[1].cov << 0.02, 0.0, 0.0, 0.02;
  for (auto& k : known) {
    k.z = plain.predict(f + Vec<3>(0.05, -0.02, 0.01), k.mean);
    ASSERT_LT((k.z - mounted.predict(f + Vec<3>(0.05, -0.02, 0.01), k.mean)).norm(), 1e-12);
  }
  const slam::PoseStep<> a{plain, f, sigma1, llt, known};
  const slam::PoseStep<implicit::robot::MountedRangeBearingSensor> b{mounted, f, sigma1, llt,
                                                                     known};
  slam::ImplicitPoseProposal implicit_b;
  implicit_b.newton = slam::pose_newton_options(50, 1e-24);
  slam::ImplicitPoseProposal implicit_a = implicit_b;
  implicit_a.point = true;
  auto compare = [&](const auto& proposal, const char* name) {
    for (std::uint64_t j = 0; j < 20; ++j) {
      Rng ra({3, 1, j, proposal.kPurpose}), rb({3, 1, j, proposal.kPurpose});
      const slam::PoseDraw da = proposal.propose(a, ra), db = proposal.propose(b, rb);
      ASSERT_FALSE(da.failed || db.failed) << name;
      EXPECT_LT((da.x - db.x).cwiseAbs().maxCoeff(), 1e-9) << name << " particle " << j;
      EXPECT_NEAR(da.log_weight, db.log_weight, 1e-9 * std::max(1.0, std::abs(da.log_weight)))
          << name << " particle " << j;
    }
  };
  compare(slam::FastSlam1Proposal{}, "fastslam1");
  compare(slam::FastSlam2Proposal{}, "fastslam2");
  compare(implicit_a, "implicit (A)");
  compare(implicit_b, "implicit (B)");
}

TEST(UserPoseProposal, BadInputIsRefused) {
  slam::SlamOptions o = options(slam::SlamMethod::kEkf, slam::Association::kKnown);
  try {
    (void)slam::pose_proposal(o);
    FAIL() << "EKF-SLAM has no pose proposal";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("EKF-SLAM is not a particle method"), std::string::npos)
        << e.what();
  }
  o.particles = 0;
  try {
    (void)slam::make_particle_slam_filter(o, slam::Pose::Zero(), UserFastSlam1{});
    FAIL() << "zero particles accepted";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("particles >= 1"), std::string::npos) << e.what();
  }
  o.particles = 5;
  const slam::Pose nan_pose(std::nan(""), 0.0, 0.0);
  try {
    (void)slam::make_particle_slam_filter(o, nan_pose, UserFastSlam1{});
    FAIL() << "non-finite initial pose accepted";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("finite initial pose"), std::string::npos) << e.what();
  }
}

}  // namespace
