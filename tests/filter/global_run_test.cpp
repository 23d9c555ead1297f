// Global localization runs, kidnapping and recovery (spec §3.11): without_steps removes exactly a
// stretch of the log, global_metrics against hand-computed values, global starts from both sources
// converge on a simulated log with an asymmetric map (and are the same for 1 and 2 threads), a
// kidnapped filter finds the robot again only with recovery, and a global start on a symmetric
// square spreads the engine's particles over the four symmetric poses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/filter/global_run.hpp"
#include "implicit/robot/simulate.hpp"

namespace implicit::filter {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Six steps at t = 0.1 k with distinguishable contents: step k has k detections, dt 0.01 (k + 1),
// truth (k, -k), fix (10 k, 0).
LocalizationProblem six_steps() {
  LocalizationProblem p;
  for (int k = 0; k < 6; ++k) {
    const double d = k;
    p.schedule.steps.push_back({0.1 * k, Control(d, 0.0), -1});
    p.step_dt.push_back(0.01 * (k + 1));
    p.detections.emplace_back(static_cast<std::size_t>(k),
                              LabelledMeasurement{Measurement(1.0, 0.0), 0});
    p.detections_total += k;
    p.truth.position.push_back(Vec<2>(d, -d));
    p.truth.heading.push_back(0.5 * k);
    p.position_fixes.push_back(Vec<2>(10.0 * k, 0.0));
  }
  return p;
}

TEST(GlobalRun, WithoutStepsRemovesExactlyTheInterval) {
  const LocalizationProblem p = six_steps();
  // [0.15, 0.35) holds the steps at 0.2 and 0.3; the bounds are not step times, so rounding of
  // 0.1 k cannot move a step across them.
  const LocalizationProblem q = without_steps(p, 0.15, 0.35);
  const std::vector<int> kept = {0, 1, 4, 5};
  ASSERT_EQ(q.schedule.steps.size(), kept.size());
  ASSERT_EQ(q.step_dt.size(), kept.size());
  ASSERT_EQ(q.detections.size(), kept.size());
  ASSERT_EQ(q.truth.position.size(), kept.size());
  ASSERT_EQ(q.truth.heading.size(), kept.size());
  ASSERT_EQ(q.position_fixes.size(), kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const int k = kept[i];
    const double d = k;
    EXPECT_EQ(q.schedule.steps[i].time, 0.1 * k);
    EXPECT_EQ(q.schedule.steps[i].u(0), k);
    // The step after the gap keeps its own length (0.05 for step 4), not the gap's 0.3 s.
    EXPECT_EQ(q.step_dt[i], 0.01 * (k + 1));
    EXPECT_EQ(q.detections[i].size(), static_cast<std::size_t>(k));
    EXPECT_EQ(q.truth.position[i], Vec<2>(d, -d));
    EXPECT_EQ(q.truth.heading[i], 0.5 * k);
    EXPECT_EQ(q.position_fixes[i], Vec<2>(10.0 * k, 0.0));
  }
  EXPECT_EQ(q.detections_total, 0 + 1 + 4 + 5);
  // An empty interval changes nothing; the start of a run at a later time drops the head.
  EXPECT_EQ(without_steps(p, 0.25, 0.25).schedule.steps.size(), 6u);
  const LocalizationProblem late = without_steps(p, -std::numeric_limits<double>::infinity(), 0.35);
  ASSERT_EQ(late.schedule.steps.size(), 2u);
  EXPECT_EQ(late.detections_total, 9);
}

TEST(GlobalRun, WithoutStepsRefusesToRemoveEverything) {
  const LocalizationProblem p = six_steps();
  try {
    without_steps(p, -1.0, 2.5);
    ADD_FAILURE() << "an empty problem was returned";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("[-1, 2.5)"), std::string::npos) << e.what();
  }
  EXPECT_THROW(without_steps(p, 0.5, 0.2), InvalidArgument);
}

// 20 steps at t = 0, 1, ..., 19 s, truth at (t, 2); the run starts at step 2. The errors are set
// per step (a mean displaced in y by e): see the table in the test.
struct MetricsCase {
  LocalizationProblem problem;
  LocalizationRun run;
  MetricsCase() {
    for (int k = 0; k < 20; ++k) {
      problem.schedule.steps.push_back({static_cast<double>(k), Control(0.0, 0.0), -1});
      problem.truth.position.push_back(Vec<2>(static_cast<double>(k), 2.0));
      problem.truth.heading.push_back(0.0);
    }
    problem.truth.position[12] = Vec<2>(kNaN, kNaN);  // no truth: skipped, does not break a stretch
    run.first_step = 2;
    for (int k = 2; k < 20; ++k) {
      double e = 0.0;
      if (k < 4)
        e = 5.0;  // before `from`: ignored
      else if (k < 8)
        e = 2.0;
      else if (k == 8)
        e = 0.5;  // below for one step only
      else if (k == 9)
        e = 3.0;
      else if (k < 17)
        e = 0.5;  // below from t = 10 on: 5 s later (t = 15) it has converged
      else
        e = 0.8;
      StepSummary s;
      s.mean = Pose(k, 2.0 + e, 0.3);
      s.particles = static_cast<std::size_t>(k % 3 == 0 ? 90 : 30);
      s.injected = k == 9 ? 7 : (k == 10 ? 4 : 0);
      run.steps.push_back(s);
    }
  }
};

TEST(GlobalRun, MetricsAgainstHandComputedValues) {
  const MetricsCase c;
  GlobalCriteria criteria;
  criteria.threshold = 1.0;
  criteria.settle = 6.0;
  const GlobalMetrics m = global_metrics(c.run, c.problem, 4.0, criteria);
  // Settled steps: t >= 10 except t = 12 (no truth): six at 0.5 m, three at 0.8 m.
  const double rmse = std::sqrt((6 * 0.25 + 3 * 0.64) / 9.0);
  EXPECT_NEAR(m.rmse_after_settle, rmse, 1e-12);
  EXPECT_TRUE(m.success);
  EXPECT_DOUBLE_EQ(m.time_to_converge, 10.0 - 4.0);
  // Steps 2..19: k = 3, 6, 9, 12, 15, 18 have 90 particles, the other twelve 30.
  EXPECT_DOUBLE_EQ(m.particles_mean, (6 * 90.0 + 12 * 30.0) / 18.0);
  EXPECT_EQ(m.particles_peak, 90.0);
  EXPECT_EQ(m.injected, 11);

  // A threshold of 0.5 m: the 0.5 m errors are not below it, so the run never converges, and the
  // RMSE (0.616 m) is a failure.
  criteria.threshold = 0.5;
  const GlobalMetrics strict = global_metrics(c.run, c.problem, 4.0, criteria);
  EXPECT_FALSE(strict.success);
  EXPECT_TRUE(std::isnan(strict.time_to_converge));
  EXPECT_NEAR(strict.rmse_after_settle, rmse, 1e-12);

  // From t = 0 with settle 0: the 2 m errors count, the first stretch of 5 s below 1 m still
  // starts at t = 10.
  criteria = {};
  criteria.settle = 0.0;
  const GlobalMetrics all = global_metrics(c.run, c.problem, 0.0, criteria);
  EXPECT_DOUBLE_EQ(all.time_to_converge, 10.0);
  const double rmse_all = std::sqrt((2 * 25.0 + 4 * 4.0 + 0.25 + 9.0 + 6 * 0.25 + 3 * 0.64) / 17.0);
  EXPECT_NEAR(all.rmse_after_settle, rmse_all, 1e-12);
  EXPECT_FALSE(all.success);
}

TEST(GlobalRun, MetricsRejectAMismatchedRun) {
  MetricsCase c;
  c.run.first_step = 3;  // 18 steps from step 3 run past the problem's 20
  EXPECT_THROW(global_metrics(c.run, c.problem, 0.0), InvalidArgument);
  GlobalCriteria bad;
  bad.threshold = 0.0;
  EXPECT_THROW(global_metrics(MetricsCase().run, c.problem, 0.0, bad), InvalidArgument);
}

// A unicycle on a 20 m square among 15 landmarks drawn uniformly over a 36 m field (seeded, so no
// symmetry: the pose is identifiable from one scan), scans every third step, labelled detections.
// Range sd 0.22 m, bearing sd 0.03 rad.
robot::RobotLog simulated_log(int steps) {
  robot::SimulationOptions o;
  o.steps = steps;
  o.route_side = 20.0;
  o.field_margin = 8.0;
  o.landmarks = 15;
  const robot::UnicycleModel model;
  return robot::simulate_robot_log(model, robot::RangeBearingSensor(),
                                   robot::square_route_driver(1.0, o.route_side, true), o, 11);
}

/// The problem with every detection's label removed: the filter associates them itself (maximum
/// likelihood at each particle), as with the car park's unlabelled detections.
LocalizationProblem unlabelled(LocalizationProblem p) {
  for (auto& scan : p.detections)
    for (LabelledMeasurement& z : scan) z.landmark = -1;
  return p;
}

/// The largest position error over the run's steps with time in [from, to).
double max_error_from(const LocalizationRun& run, const LocalizationProblem& problem, double from,
                      double to = std::numeric_limits<double>::infinity()) {
  double worst = 0.0;
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    const std::size_t n = run.first_step + k;
    const double t = problem.schedule.steps[n].time;
    if (t < from || t >= to) continue;
    worst = std::max(worst, (run.steps[k].mean.head<2>() - problem.truth.position[n]).norm());
  }
  return worst;
}

template <typename Proposal>
LocalizationRun global_run(const LocalizationProblem& problem, const Proposal& proposal,
                           GlobalSource source, std::size_t particles) {
  FilterOptions options;
  options.particles = particles;
  options.seed = 5;
  GlobalOptions g;
  g.source = source;
  return run_global_localization(problem, robot::UnicycleModel(), robot::RangeBearingSensor(),
                                 proposal, options, g);
}

// The bound: with 3-8 detections per scan (range sd 0.22 m, bearing sd 0.03 rad) the posterior
// position sd is about 0.1 m (see any_robot_test.cpp), so 0.5 m is 5 sd; a filter on a wrong pose
// is metres off. Labelled detections: both sources. The uniform cloud (AMCL's way) needs
// particles near the true pose; labelled detections keep the likelihood informative at any
// distance, so 20000 over the 46 m x 46 m x 2 pi box suffice. Unlabelled ones are gated: only
// particles very near the true pose count (with 20000, this seed's uniform start stays 45 m off);
// the mixture over the minima finds the pose from the first scan either way.
TEST(GlobalRun, BothSourcesConvergeOnAnAsymmetricMap) {
  const robot::UnicycleModel model;
  const LocalizationProblem labelled = make_problem(simulated_log(400), model.dt());
  const LocalizationProblem unlabelled_problem = unlabelled(labelled);
  const double from = labelled.schedule.steps.front().time + 10.0;
  const LocalizationRun mixture =
      global_run(labelled, ImplicitProposal{}, GlobalSource::kMixture, 100);
  const LocalizationRun uniform =
      global_run(labelled, BootstrapProposal{}, GlobalSource::kUniform, 20000);
  const LocalizationRun mixture_unlabelled =
      global_run(unlabelled_problem, ImplicitProposal{}, GlobalSource::kMixture, 100);
  const double e_mixture = max_error_from(mixture, labelled, from);
  const double e_uniform = max_error_from(uniform, labelled, from);
  const double e_unlabelled = max_error_from(mixture_unlabelled, unlabelled_problem, from);
  std::printf("max error from 10 s: mixture %.3f m, uniform %.3f m, mixture unlabelled %.3f m\n",
              e_mixture, e_uniform, e_unlabelled);
  EXPECT_FALSE(mixture.uniform_start);
  EXPECT_FALSE(mixture_unlabelled.uniform_start);
  EXPECT_LT(e_mixture, 0.5);
  EXPECT_LT(e_uniform, 0.5);
  EXPECT_LT(e_unlabelled, 0.5);
}

// The steps of [20, 26) s are dropped: the robot moves about 6 m and turns the square's first
// corner (at about 20 s) unseen. The filter starts from the known pose.
LocalizationRun kidnapped_run(const LocalizationProblem& problem, bool recovery) {
  FilterOptions options;
  options.particles = 100;
  options.seed = 5;
  options.recovery.enabled = recovery;
  GlobalOptions g;
  g.global_start = false;
  g.source = GlobalSource::kMixture;
  return run_global_localization(problem, robot::UnicycleModel(), robot::RangeBearingSensor(),
                                 ImplicitProposal{}, options, g);
}

TEST(GlobalRun, KidnappedFilterRecoversOnlyWithRecovery) {
  const LocalizationProblem full = make_problem(simulated_log(500), robot::UnicycleModel().dt());
  const double gap_from = 20.0, gap_to = 26.0;
  const LocalizationProblem problem = unlabelled(without_steps(full, gap_from, gap_to));
  std::size_t after = 0;
  while (problem.schedule.steps[after].time < gap_to) ++after;
  ASSERT_GT((problem.truth.position[after] - problem.truth.position[after - 1]).norm(), 4.0);
  GlobalCriteria criteria;
  criteria.threshold = 0.5;
  criteria.settle = 10.0;
  const LocalizationRun with = kidnapped_run(problem, true);
  const LocalizationRun without = kidnapped_run(problem, false);
  const GlobalMetrics m_with = global_metrics(with, problem, gap_to, criteria);
  const GlobalMetrics m_without = global_metrics(without, problem, gap_to, criteria);
  std::printf(
      "after the gap + 10 s: rmse with recovery %.3f m (converged after %.1f s, %d "
      "injected), without %.3f m\n",
      m_with.rmse_after_settle, m_with.time_to_converge, m_with.injected,
      m_without.rmse_after_settle);
  // Both were on the robot before the gap: the error after it is the kidnapping's.
  EXPECT_LT(max_error_from(with, problem, 0.0, gap_from), 0.5);
  EXPECT_LT(max_error_from(without, problem, 0.0, gap_from), 0.5);
  EXPECT_TRUE(m_with.success);
  EXPECT_LT(max_error_from(with, problem, gap_to + criteria.settle), 0.5);
  EXPECT_GT(m_with.injected, 0);
  EXPECT_FALSE(m_without.success);
  EXPECT_GT(m_without.rmse_after_settle, 2.0);
  EXPECT_EQ(m_without.injected, 0);
}

// Every random draw is keyed by (seed, step, particle), so the runs are bit-identical for any
// thread count: a global start (mode search, mixture draws) and a kidnapped run with injections.
TEST(GlobalRun, SameRunsForOneAndTwoThreads) {
  const LocalizationProblem full =
      unlabelled(make_problem(simulated_log(500), robot::UnicycleModel().dt()));
  const LocalizationProblem kidnapped = without_steps(full, 20.0, 26.0);
  std::vector<LocalizationRun> global, recovered;
  for (int threads : {1, 2}) {
    const ThreadLimit limit(threads);
    global.push_back(global_run(full, ImplicitProposal{}, GlobalSource::kMixture, 100));
    recovered.push_back(kidnapped_run(kidnapped, true));
  }
  for (const auto* runs : {&global, &recovered}) {
    const LocalizationRun &a = (*runs)[0], &b = (*runs)[1];
    ASSERT_EQ(a.steps.size(), b.steps.size());
    for (std::size_t k = 0; k < a.steps.size(); ++k) {
      ASSERT_EQ(a.steps[k].injected, b.steps[k].injected) << "step " << k;
      for (int i = 0; i < 3; ++i) ASSERT_EQ(a.steps[k].mean(i), b.steps[k].mean(i)) << "step " << k;
    }
  }
  EXPECT_GT(global_metrics(recovered[0], kidnapped, 26.0).injected, 0);
}

// Four landmarks on a square, seen unlabelled from its centre: the detections fit four poses
// (the centre, headings a quarter turn apart), so the global start's particles, as the engine holds
// them after initialize(), form four clusters of about a quarter of the weight each.
TEST(GlobalRun, SymmetricSquareSpreadsTheStartOverFourPoses) {
  robot::LandmarkMap map;
  const std::vector<Landmark> square = {Landmark(10, 10), Landmark(-10, 10), Landmark(-10, -10),
                                        Landmark(10, -10)};
  for (std::size_t i = 0; i < square.size(); ++i) map.add(static_cast<int>(i), square[i]);
  const robot::RangeBearingSensor sensor;
  std::vector<LabelledMeasurement> z;
  for (const Landmark& m : square) z.push_back({sensor.predict(Pose(0, 0, 0.4), m), -1});
  FilterOptions options;
  options.particles = 4000;
  options.seed = 9;
  ParticleFilter pf(robot::UnicycleModel(), sensor, map, ImplicitProposal{}, options);
  const auto ctx = pf.context(z);
  const PoseBounds bounds = map_bounds(map.positions(), 5.0);
  const auto modes = find_pose_modes(ctx, bounds, GlobalInitOptions{});
  std::vector<Pose> x(options.particles);
  std::vector<double> lw(options.particles);
  sample_pose_mixture(ctx, modes, bounds, options.seed, 0, x, lw, 0.1);
  pf.initialize(x, lw);

  // Clusters: each particle joins the first centre within 1 m and 0.5 rad, else starts one.
  std::vector<Pose> centres;
  std::vector<double> mass;
  double sum_sq = 0.0;
  for (std::size_t j = 0; j < pf.size(); ++j) {
    const Pose& p = pf.particles()[j];
    const double w = pf.weights()[j];
    sum_sq += w * w;
    std::size_t c = 0;
    while (c < centres.size() && ((p.head<2>() - centres[c].head<2>()).norm() > 1.0 ||
                                  std::abs(wrap_angle(p(2) - centres[c](2))) > 0.5))
      ++c;
    if (c == centres.size()) {
      centres.push_back(p);
      mass.push_back(0.0);
    }
    mass[c] += w;
  }
  std::vector<double> heavy;
  for (std::size_t c = 0; c < centres.size(); ++c)
    if (mass[c] > 0.05) heavy.push_back(mass[c]);
  ASSERT_EQ(heavy.size(), 4u);
  // Each cluster's mass estimates 1/4 with standard error about sqrt(1/4 * 3/4 / ESS).
  const double se = std::sqrt(0.25 * 0.75 * sum_sq);
  for (double h : heavy) EXPECT_NEAR(h, 0.25, 5 * se);
}

}  // namespace
}  // namespace implicit::filter
