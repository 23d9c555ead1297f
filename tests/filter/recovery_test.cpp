// Recovery of a lost filter (spec §3.11): the injection probability follows augmented MCL's
// formula on the per-detection likelihood, injected particles get the extended-space weights
// log(eps / p) + (the source's value) and the others log((1 - eps) / (1 - p)), the injected count
// is binomial(M, p), a filter whose averages never drop is bit-identical to one without recovery,
// and weighted initialisation normalises the given log weights.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <set>
#include <tuple>
#include <vector>

#include "implicit/core/parallel.hpp"
#include "implicit/filter/particle_filter.hpp"
#include "implicit/filter/recovery.hpp"

namespace implicit::filter {
namespace {

using robot::LandmarkMap;
using robot::RangeBearingSensor;
using robot::UteModel;

// AMCL's update of w_slow, w_fast (Probabilistic Robotics, Table 8.3) in plain arithmetic, the
// independent formula the log-space class is checked against.
struct PlainAverages {
  double slow = 0.0, fast = 0.0;
  void update(double w, double a_slow, double a_fast) {
    if (slow == 0.0) {
      slow = fast = w;
      return;
    }
    slow += a_slow * (w - slow);
    fast += a_fast * (w - fast);
  }
  double p(double cap) const { return std::min(cap, std::max(0.0, 1.0 - fast / slow)); }
};

TEST(Recovery, InjectionProbabilityFollowsTheFormula) {
  RecoveryOptions o;
  o.recovery_alpha_slow = 0.01;
  o.recovery_alpha_fast = 0.3;
  o.max_injection = 0.9;
  LikelihoodAverages avg;
  PlainAverages plain;
  EXPECT_EQ(avg.injection_probability(o), 0.0);
  // A filter that fits well for 50 steps, then badly (increments per detection drop by 3).
  for (int k = 0; k < 80; ++k) {
    const int detections = 1 + k % 4;
    const double per_detection = k < 50 ? 0.5 + 0.1 * std::sin(k) : -2.5;
    avg.update(per_detection * detections, detections, o);
    plain.update(std::exp(per_detection), o.recovery_alpha_slow, o.recovery_alpha_fast);
    EXPECT_NEAR(avg.injection_probability(o), plain.p(o.max_injection), 1e-12) << "step " << k;
  }
  EXPECT_GT(avg.injection_probability(o), 0.5);  // lost: the fast average fell far below
  avg.update(0.0, 0, o);                         // no detections: nothing changes
  EXPECT_NEAR(avg.injection_probability(o), plain.p(o.max_injection), 1e-12);
}

TEST(Recovery, RejectsBadOptions) {
  RecoveryOptions o;
  o.recovery_alpha_fast = o.recovery_alpha_slow / 2;
  EXPECT_THROW(validate(o), InvalidArgument);
  o = {};
  o.kidnap_probability = 0.0;
  EXPECT_THROW(validate(o), InvalidArgument);
  o = {};
  o.max_injection = 1.0;
  EXPECT_THROW(validate(o), InvalidArgument);
}

// A proposal that keeps the pose and returns the increment the test sets: the weights are then
// known in closed form.
struct FixedProposal {
  static constexpr std::uint64_t kPurpose = purpose::kProposal;
  const double* increment = nullptr;
  template <typename Ctx>
  double propose(const Ctx&, const Pose& previous, Rng&, Pose& next, ParticleStats&) const {
    next = previous;
    return *increment;
  }
};

// Puts every drawn particle at one pose with a fixed value of log u + log p(z|x) - log g.
template <typename Ctx>
class FixedSource : public RecoverySource<Ctx> {
 public:
  FixedSource(Pose at, double value) : at_(at), value_(value) {}
  bool prepare(const Ctx&) override {
    ++prepared;
    return true;
  }
  double draw(const Ctx&, Rng&, Pose& x) const override {
    x = at_;
    return value_;
  }
  int prepared = 0;

 private:
  Pose at_;
  double value_;
};

using Filter = ParticleFilter<UteModel, RangeBearingSensor, FixedProposal>;

RecoveryOptions test_recovery() {
  RecoveryOptions r;
  r.enabled = true;
  r.recovery_alpha_slow = 0.05;
  r.recovery_alpha_fast = 0.5;
  r.kidnap_probability = 0.01;
  r.max_injection = 0.5;
  return r;
}

Filter make_filter(std::size_t m, const double* increment, bool recovery) {
  LandmarkMap map;
  map.add(1, Landmark(5, 5));
  FilterOptions o;
  o.particles = m;
  o.resample_threshold = 0.0;  // never: the weights stay observable
  o.seed = 3;
  o.recovery = test_recovery();
  o.recovery.enabled = recovery;
  // The detections here are placeholders that FixedProposal never reads; the prediction gate
  // on labels (label_gate_test.cpp) would rightly leave them out, so it is off.
  o.association.label_gate = 0.0;
  return Filter(UteModel(), RangeBearingSensor(), map, FixedProposal{increment}, o);
}

TEST(Recovery, WeightsOfBothBranchesAndTheInjectedCount) {
  const std::size_t m = 20000;
  double increment = 0.0;
  Filter pf = make_filter(m, &increment, true);
  const Pose far(100.0, -50.0, 1.0);
  const double value = -2.0;
  auto source = std::make_shared<FixedSource<Filter::Context>>(far, value);
  pf.set_recovery_source(source);
  pf.initialize(Pose::Zero(), Mat3::Identity() * 0.01);
  const std::vector<LabelledMeasurement> z(2, LabelledMeasurement{Measurement(7.0, 0.8), 0});
  const Control u(0.0, 0.0);
  const RecoveryOptions ro = test_recovery();
  const double eps = ro.kidnap_probability;
  LikelihoodAverages expected;
  for (int k = 0; k < 5; ++k) {  // a good fit: nothing is injected, the source is not asked
    pf.step(u, z);
    expected.update(std::log1p(-eps), 2, ro);
    EXPECT_EQ(pf.last().injected, 0);
  }
  EXPECT_EQ(source->prepared, 0);
  increment = -8.0;  // the fit drops: this step still uses the old averages (p = 0) ...
  pf.step(u, z);
  expected.update(-8.0 + std::log1p(-eps), 2, ro);
  EXPECT_EQ(pf.last().injected, 0);
  EXPECT_NEAR(pf.likelihood_averages().log_fast(), expected.log_fast(), 1e-12);
  EXPECT_NEAR(pf.likelihood_averages().log_slow(), expected.log_slow(), 1e-12);
  const double p = expected.injection_probability(ro);
  ASSERT_GT(p, 0.1);
  const std::vector<double> before(pf.weights().begin(), pf.weights().end());
  for (double w : before) ASSERT_NEAR(w, 1.0 / m, 1e-15);  // all equal so far
  pf.step(u, z);  // ... and this one injects a binomial(M, p) number of particles
  EXPECT_EQ(source->prepared, 1);
  EXPECT_DOUBLE_EQ(pf.last().injection_probability, p);
  const double n = static_cast<double>(pf.last().injected);
  const double se = std::sqrt(m * p * (1 - p));
  EXPECT_NEAR(n, m * p, 4.5 * se) << "binomial count, 4.5 standard errors";
  // Weights: injected log(eps/p) + value, kept -8 + log((1-eps)/(1-p)), normalised together.
  const double li = std::log(eps / p) + value, lk = -8.0 + std::log((1 - eps) / (1 - p));
  const double total = n * std::exp(li) + (m - n) * std::exp(lk);
  int seen = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const bool injected = pf.particles()[j] == far;
    seen += injected ? 1 : 0;
    const double w = (injected ? std::exp(li) : std::exp(lk)) / total;
    ASSERT_NEAR(pf.weights()[j], w, 1e-12 * w) << j;
  }
  EXPECT_EQ(seen, pf.last().injected);
  EXPECT_NEAR(pf.last().log_likelihood_increment, std::log(total / m), 1e-12);
}

TEST(Recovery, WithoutADropItIsBitIdenticalToNoRecovery) {
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    const double increment = -1.0;
    Filter a = make_filter(300, &increment, false), b = make_filter(300, &increment, true);
    auto source = std::make_shared<FixedSource<Filter::Context>>(Pose::Zero(), 0.0);
    b.set_recovery_source(source);
    a.initialize(Pose(1, 2, 0.3), Mat3::Identity() * 0.04);
    b.initialize(Pose(1, 2, 0.3), Mat3::Identity() * 0.04);
    const std::vector<LabelledMeasurement> z(3, LabelledMeasurement{Measurement(7.0, 0.8), 0});
    for (int k = 0; k < 20; ++k) {
      const auto& sa = a.step(Control(1.0, 0.05), k % 2 ? z : std::vector<LabelledMeasurement>{});
      const auto& sb = b.step(Control(1.0, 0.05), k % 2 ? z : std::vector<LabelledMeasurement>{});
      ASSERT_EQ(sa.mean, sb.mean) << k;
      ASSERT_EQ(sb.injected, 0);
    }
    for (std::size_t j = 0; j < a.size(); ++j) ASSERT_EQ(a.weights()[j], b.weights()[j]);
    EXPECT_EQ(source->prepared, 0);
  }
}

TEST(WeightedInitialization, NormalisesAndResizes) {
  const double increment = 0.0;
  Filter pf = make_filter(10, &increment, false);
  const std::vector<Pose> x = {Pose(0, 0, 0), Pose(1, 0, 0), Pose(2, 0, 0)};
  const std::vector<double> lw = {std::log(1.0) - 700, std::log(2.0) - 700, std::log(1.0) - 700};
  pf.initialize(x, lw);
  ASSERT_EQ(pf.size(), 3u);
  // exp(l - total) with |l| ~ 700 loses ~700 ulp: 1e-12 is round-off, not tuning.
  EXPECT_NEAR(pf.weights()[1], 0.5, 1e-12);
  EXPECT_NEAR(pf.last().mean(0), 1.0, 1e-12);
  EXPECT_NEAR(pf.last().ess, 16.0 / 6.0, 1e-12);  // 1 / sum w^2 = 1 / (1/16 + 1/4 + 1/16)
  EXPECT_EQ(pf.last().particles, 3u);
  const std::vector<double> dead(3, -std::numeric_limits<double>::infinity());
  EXPECT_THROW(pf.initialize(x, dead), InvalidArgument);
  EXPECT_THROW(pf.initialize(x, std::vector<double>(2, 0.0)), InvalidArgument);
}

// KLD-sampling in the engine: the count follows the occupied bins at every update step.
TEST(KldEngine, ParticleCountFollowsTheBins) {
  const double increment = 0.0;
  LandmarkMap map;
  map.add(1, Landmark(5, 5));
  FilterOptions o;
  o.particles = 3000;
  o.seed = 11;
  o.kld.enabled = true;
  o.kld.min_particles = 50;
  o.kld.max_particles = 4000;
  o.association.label_gate = 0.0;  // placeholder detections, as in make_filter
  const std::vector<LabelledMeasurement> z(1, LabelledMeasurement{Measurement(7.0, 0.8), 0});
  for (double spread : {1e-6, 25.0}) {
    Filter pf(UteModel(), RangeBearingSensor(), map, FixedProposal{&increment}, o);
    pf.initialize(Pose(0.25, 0.25, 0.08), Mat3::Identity() * spread);  // a bin centre
    const StepSummary& s = pf.step(Control(0.0, 0.0), z);
    ASSERT_TRUE(s.resampled);
    ASSERT_EQ(s.particles, pf.size());
    // Recount the bins of the resampled set: the count is the KLD count of those bins.
    std::set<std::tuple<long, long, long>> bins;
    for (const Pose& x : pf.particles())
      bins.emplace(std::lround(std::floor(x(0) / o.kld.bin_xy)),
                   std::lround(std::floor(x(1) / o.kld.bin_xy)),
                   std::lround(std::floor(wrap_angle(x(2)) / o.kld.bin_heading)));
    EXPECT_EQ(pf.size(), kld_particle_count(bins.size(), o.kld)) << "spread " << spread;
    if (spread < 1.0) {
      EXPECT_EQ(pf.size(), o.kld.min_particles);
    } else {
      EXPECT_GT(pf.size(), 1000u);
    }
    const StepSummary& p = pf.step(Control(0.0, 0.0), {});  // prediction keeps the count
    EXPECT_EQ(p.particles, pf.size());
  }
}

}  // namespace
}  // namespace implicit::filter
