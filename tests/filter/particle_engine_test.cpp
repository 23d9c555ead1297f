// The generic sequential Monte Carlo engine (filter/particle_engine.hpp) and the pose collector
// (filter/pose_moments.hpp): reweighting against closed forms, resampling bookkeeping, bad
// increments, thread-count independence, the bootstrap estimate of a Gaussian evidence against
// its closed form, and the circular mean across the heading cut.
#include "implicit/filter/particle_engine.hpp"
#include "implicit/filter/pose_moments.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::filter {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A particle that is not a vector: the engine must not care what it moves.
struct Walker {
  double position = 0.0;
  std::vector<int> history;
};

TEST(ParticleEngine, ReweightMatchesTheClosedForm) {
  ParticleEngine<Walker> e(4, Walker{});
  const std::vector<double> a = {0.0, std::log(2.0), std::log(3.0), -kInf};
  e.move([&](std::size_t j, Walker& w) {
    w.history.push_back(static_cast<int>(j));
    return a[j];
  });
  const Reweighting r = e.reweight();
  // Uniform previous weights 1/4: w_j = exp(a_j) / 6, log Z increment = log(6 / 4).
  EXPECT_NEAR(r.log_likelihood_increment, std::log(1.5), 1e-15);
  const std::vector<double> expected = {1.0 / 6, 2.0 / 6, 3.0 / 6, 0.0};
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(e.weights()[j], expected[j], 1e-15) << j;
    EXPECT_EQ(e.particles()[j].history, std::vector<int>{static_cast<int>(j)});
  }
  EXPECT_EQ(e.log_weights()[3], -kInf);
  EXPECT_NEAR(r.ess, 1.0 / (1.0 / 36 + 4.0 / 36 + 9.0 / 36), 1e-13);
  EXPECT_FALSE(r.all_weights_zero);
}

TEST(ParticleEngine, TwoReweightingsEqualOneWithTheSummedIncrements) {
  const std::vector<double> a = {0.3, -1.2, 2.5, 0.0, -0.7}, b = {1.1, 0.4, -2.0, 0.9, 0.2};
  ParticleEngine<double> twice(5, 0.0), once(5, 0.0);
  twice.move([&](std::size_t j, double&) { return a[j]; });
  const double l1 = twice.reweight().log_likelihood_increment;
  twice.move([&](std::size_t j, double&) { return b[j]; });
  const double l2 = twice.reweight().log_likelihood_increment;
  once.move([&](std::size_t j, double&) { return a[j] + b[j]; });
  const double l = once.reweight().log_likelihood_increment;
  // The increments multiply: log Z is additive over steps.
  EXPECT_NEAR(l1 + l2, l, 1e-13);
  for (std::size_t j = 0; j < 5; ++j) EXPECT_NEAR(twice.weights()[j], once.weights()[j], 1e-14);
}

TEST(ParticleEngine, AllIncrementsMinusInfinityLeaveUniformWeightsAndSaySo) {
  ParticleEngine<double> e(3, 1.0);
  e.move([](std::size_t j, double&) { return j == 0 ? 5.0 : 0.0; });
  e.reweight();
  e.move([](std::size_t, double&) { return -kInf; });
  const Reweighting r = e.reweight();
  EXPECT_TRUE(r.all_weights_zero);
  EXPECT_EQ(r.log_likelihood_increment, -kInf);
  EXPECT_DOUBLE_EQ(r.ess, 3.0);
  for (double w : e.weights()) EXPECT_DOUBLE_EQ(w, 1.0 / 3.0);
}

TEST(ParticleEngine, ANanOrInfiniteIncrementNamesTheParticle) {
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), kInf}) {
    ParticleEngine<double> e(4, 0.0);
    e.move([&](std::size_t j, double&) { return j == 2 ? bad : 0.0; });
    try {
      e.reweight();
      ADD_FAILURE() << "no error for increment " << bad;
    } catch (const InvalidArgument& ex) {
      EXPECT_NE(std::string(ex.what()).find("particle 2"), std::string::npos) << ex.what();
    }
  }
}

TEST(ParticleEngine, ResampleKeepsThePopulationBeforeItUntilTheNextMove) {
  ParticleEngine<double> e(3, 0.0);
  e.move([](std::size_t j, double& x) {
    x = 10.0 * static_cast<double>(j);
    return j == 1 ? std::log(2.0) : 0.0;
  });
  e.reweight();
  const std::vector<std::size_t> ancestors = {1, 1, 2, 0};  // the count may change (KLD)
  e.resample(ancestors);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(std::vector<double>(e.particles().begin(), e.particles().end()),
            (std::vector<double>{10.0, 10.0, 20.0, 0.0}));
  for (double w : e.weights()) EXPECT_DOUBLE_EQ(w, 0.25);
  ASSERT_TRUE(e.resampled());
  EXPECT_EQ(std::vector<double>(e.before_resampling().begin(), e.before_resampling().end()),
            (std::vector<double>{0.0, 10.0, 20.0}));
  EXPECT_NEAR(e.weights_before_resampling()[1], 0.5, 1e-15);
  e.move([](std::size_t, double&) { return 0.0; });
  EXPECT_FALSE(e.resampled());
  EXPECT_THROW(e.resample(std::vector<std::size_t>{0, 4}), InvalidArgument);
}

// Particles that share state (grid SLAM's maps share tiles): the kept population holds
// references until it is released, after which a particle not drawn is freed and a drawn one is
// held by its descendants alone.
TEST(ParticleEngine, ReleasingThePopulationBeforeResamplingDropsItsReferences) {
  ParticleEngine<std::shared_ptr<int>> e(3, nullptr);
  e.move([](std::size_t j, std::shared_ptr<int>& p) {
    p = std::make_shared<int>(static_cast<int>(j));
    return 0.0;
  });
  e.reweight();
  const std::weak_ptr<int> not_drawn = e.particles()[1];
  const std::weak_ptr<int> drawn_once = e.particles()[2];
  e.resample(std::vector<std::size_t>{0, 0, 2});
  EXPECT_EQ(e.particles()[0].use_count(), 3);  // two descendants and the kept population
  EXPECT_EQ(drawn_once.use_count(), 2);
  EXPECT_FALSE(not_drawn.expired());
  e.release_before_resampling();
  EXPECT_TRUE(e.before_resampling().empty());
  EXPECT_TRUE(e.weights_before_resampling().empty());
  EXPECT_EQ(e.particles()[0].use_count(), 2);
  EXPECT_EQ(drawn_once.use_count(), 1);  // a write to it need not copy
  EXPECT_TRUE(not_drawn.expired());
  EXPECT_EQ(*e.particles()[2], 2);
  // The engine goes on as before: the next resampling keeps its population again.
  e.reweight();
  e.resample(std::vector<std::size_t>{2, 1, 0});
  ASSERT_EQ(e.before_resampling().size(), 3u);
  EXPECT_EQ(*e.particles()[0], 2);
}

TEST(ParticleEngine, AssignNormalisesLogWeightsAndRefusesAZeroTotal) {
  ParticleEngine<double> e;
  const std::vector<double> xs = {1.0, 2.0}, lw = {std::log(3.0) + 100.0, 100.0};
  e.assign(xs, lw);
  // Differences of log weights near 101 are exact to a few ulp(101) = 1.4e-14 each.
  EXPECT_NEAR(e.weights()[0], 0.75, 1e-13);
  EXPECT_NEAR(e.weights()[1], 0.25, 1e-13);
  const std::vector<double> zero = {-kInf, -kInf};
  EXPECT_THROW(e.assign(xs, zero), InvalidArgument);
  EXPECT_THROW(e.assign(0, 1.0), InvalidArgument);
}

// One bootstrap step of x ~ N(0, s^2), y | x ~ N(x, 1): the engine's log-likelihood increment
// estimates log p(y) = log N(y; 0, s^2 + 1), and the weighted mean estimates E[x | y] =
// y s^2 / (s^2 + 1). Tolerances: 5 delta-method standard errors, estimated from the sample.
ParticleEngine<double> bootstrap_step(std::size_t m, double s, double y, Reweighting& r) {
  ParticleEngine<double> e(m, 0.0);
  e.move([&](std::size_t j, double& x) {
    Rng rng({7, 1, j, purpose::kProposal});
    x = s * rng.normal();
    return -0.5 * std::log(2.0 * kPi) - 0.5 * (y - x) * (y - x);
  });
  r = e.reweight();
  return e;
}

TEST(ParticleEngine, BootstrapStepEstimatesTheGaussianEvidenceAndPosteriorMean) {
  const std::size_t m = 20000;
  const double s = 2.0, y = 1.5;
  Reweighting r;
  const ParticleEngine<double> e = bootstrap_step(m, s, y, r);
  const double v = s * s + 1.0;
  const double log_z = -0.5 * std::log(2.0 * kPi * v) - 0.5 * y * y / v;
  // log Z-hat: standard error sd(w) / (sqrt(M) mean(w)) of the raw weights (relative).
  std::vector<double> raw(m);
  for (std::size_t j = 0; j < m; ++j) raw[j] = e.log_weights()[j] + r.log_likelihood_increment;
  const double se_log_z = relative_standard_error(raw);
  EXPECT_NEAR(r.log_likelihood_increment, log_z, 5.0 * se_log_z);
  double mean = 0.0;
  for (std::size_t j = 0; j < m; ++j) mean += e.weights()[j] * e.particles()[j];
  double var_mean = 0.0;  // delta method for a self-normalised estimate
  for (std::size_t j = 0; j < m; ++j)
    var_mean += e.weights()[j] * e.weights()[j] * std::pow(e.particles()[j] - mean, 2);
  EXPECT_NEAR(mean, y * s * s / v, 5.0 * std::sqrt(var_mean));
  EXPECT_GT(se_log_z, 0.0);
}

TEST(ParticleEngine, TheResultDoesNotDependOnTheThreadCount) {
  std::vector<double> w1, w2, x1, x2;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    Reweighting r;
    ParticleEngine<double> e = bootstrap_step(5000, 1.0, 0.3, r);
    Rng rng({7, 1, 0, purpose::kResampling});
    e.resample(resample(ResamplingScheme::kSystematic, e.weights(), e.size(), rng));
    e.move([](std::size_t j, double& x) {
      Rng g({7, 2, j, purpose::kProposal});
      x += g.normal();
      return -0.5 * x * x;
    });
    e.reweight();
    (threads == 1 ? w1 : w2).assign(e.weights().begin(), e.weights().end());
    (threads == 1 ? x1 : x2).assign(e.particles().begin(), e.particles().end());
  }
  EXPECT_EQ(w1, w2);
  EXPECT_EQ(x1, x2);
}

}  // namespace
}  // namespace implicit::filter

namespace implicit::filter {
namespace {

// Two poses on either side of the heading cut at +-pi: the circular mean is pi (not 0), the
// heading deviations are +-0.1 (wrapped), and keep_branch puts the mean on the first pose's
// branch (3 pi here, an unwrapped heading).
TEST(PoseMoments, CircularMeanAndWrappedCovarianceAgainstTheClosedForm) {
  const std::vector<Vec<3>> poses = {Vec<3>(1.0, 0.0, kPi - 0.1), Vec<3>(3.0, 2.0, -kPi + 0.1)};
  const std::vector<double> w = {0.5, 0.5};
  auto pose_of = [](const Vec<3>& x) -> const Vec<3>& { return x; };
  PoseMoments moments;
  const auto& m = moments(poses, w, pose_of);
  EXPECT_NEAR(m.mean(0), 2.0, 1e-15);
  EXPECT_NEAR(m.mean(1), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(m.mean(2)), kPi, 1e-14);
  EXPECT_NEAR(m.covariance(0, 0), 1.0, 1e-14);
  EXPECT_NEAR(m.covariance(0, 1), 1.0, 1e-14);
  EXPECT_NEAR(m.covariance(2, 2), 0.01, 1e-14);
  EXPECT_NEAR(m.covariance(0, 2), 0.1, 1e-14);  // deviations (-1, -0.1) and (1, 0.1)
  std::vector<Vec<3>> unwrapped = poses;
  unwrapped[0](2) += 2.0 * kPi;
  PoseMoments branch(true);
  EXPECT_NEAR(branch(unwrapped, w, pose_of).mean(2), 3.0 * kPi, 1e-13);
}

}  // namespace
}  // namespace implicit::filter
