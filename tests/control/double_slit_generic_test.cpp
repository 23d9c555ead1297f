// The paper's double slit through the generic problem type (double_slit_problem.hpp): the
// generic estimators against the exact solution of spec §2.4.1.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "implicit/control/double_slit_problem.hpp"
#include "implicit/control/path_integral.hpp"
#include "implicit/core/error.hpp"

using namespace implicit::control;
using implicit::Vec;

namespace {

// Table 1, and a variant where every parameter differs (sigma != 1 so gamma != r, asymmetric
// slits, another wall time and grid): a problem built from constants instead of the parameters
// fails on one of them.
DoubleSlitParameters variant(int v) {
  DoubleSlitParameters p;
  if (v == 1) {
    p.sigma = 0.5;
    p.control_cost = 0.2;
    p.slits = {{{-3.0, -1.0}, {2.0, 5.0}}};
    p.wall_time = 0.6;
    p.final_time = 1.5;
    p.dt = 0.03;
  }
  return p;
}

struct Point {
  int variant;
  double x, t;
};

// States before the wall, inside a slit's shadow (x within a slit) and outside it (between the
// slits, where one or both slits matter, and beyond them), far from and close to t1.
constexpr Point kPoints[] = {{0, 1.0, 0.0},  {0, 1.9, 0.0},  {0, 3.0, 0.3},  {0, -5.0, 0.5},
                             {0, 10.0, 0.5}, {0, 7.0, 0.8},  {0, -2.0, 0.9}, {1, 1.0, 0.0},
                             {1, 0.0, 0.3},  {1, -2.0, 0.3}, {1, 3.0, 0.3},  {1, 10.0, 0.51}};

int step_of(const DoubleSlit& slit, double t) {
  return static_cast<int>(std::lround(t / slit.parameters().dt));
}

}  // namespace

TEST(DoubleSlitGeneric, ProblemMatchesTheParameters) {
  for (int v : {0, 1}) {
    const DoubleSlitParameters p = variant(v);
    const DoubleSlit slit(p);
    const auto problem = double_slit_problem(p);
    EXPECT_DOUBLE_EQ(problem.gamma(), slit.gamma());  // condition (8): gamma = r sigma
    EXPECT_EQ(problem.num_steps(), slit.num_steps());
    ASSERT_EQ(problem.walls().size(), 1u);
    EXPECT_EQ(problem.wall_step(0), slit.wall_step());
    ASSERT_EQ(problem.walls()[0].openings.size(), 2u);
    for (int s = 0; s < 2; ++s) {
      EXPECT_EQ(problem.walls()[0].openings[s].lower, p.slits[s].lower);
      EXPECT_EQ(problem.walls()[0].openings[s].upper, p.slits[s].upper);
    }
  }
  DoubleSlitParameters bad;
  bad.slits = {{{6.0, 8.0}, {-6.0, -4.0}}};
  EXPECT_THROW(double_slit_problem(bad), implicit::InvalidArgument);
  bad = {};
  bad.wall_time = 1.01;  // not a grid time
  EXPECT_THROW(double_slit_problem(bad), implicit::InvalidArgument);
}

TEST(DoubleSlitGeneric, LogPsiAgreesWithTheExactSolution) {
  // Forward Euler is exact in law for dx = sqrt(sigma) dW and the wall acts at a grid time, so
  // E[psi_hat] is the exact psi; log psi_hat is off by its standard error, the relative SE of the
  // weights (bias O(1/M), far below it). Tolerance 4.5 SE; with M = 4000 the SE is 0.004-0.08,
  // so moving an opening by 0.05, gamma or sigma by 5 % or the wall by one step fails some point.
  const int M = 4000;
  for (const auto& pt : kPoints) {
    const DoubleSlit slit(variant(pt.variant));
    const auto problem = double_slit_problem(variant(pt.variant));
    const int k = step_of(slit, pt.t);
    ASSERT_LT(k, slit.wall_step());
    const double exact = slit.exact_log_psi(pt.x, slit.time(k));
    for (auto map : {SamplingMap::kLinear, SamplingMap::kRandom}) {
      const auto e = estimate_log_psi_implicit(problem, Vec<1>(pt.x), k, M, {41}, {}, {}, map);
      ASSERT_EQ(e.modes.size(), 2u);
      EXPECT_EQ(e.map_failures, 0);
      EXPECT_GT(e.relative_se, 0.0);
      EXPECT_LT(e.relative_se, 0.1);
      EXPECT_NEAR(e.log_psi, exact, 4.5 * e.relative_se)
          << "variant " << pt.variant << ", x = " << pt.x << ", k = " << k << ", " << to_string(map)
          << " map";
    }
  }
}

TEST(DoubleSlitGeneric, PlainMonteCarloAgreesWhereItCanPass) {
  // Plain Monte Carlo only works where many paths pass and few carry all the weight: in the
  // variant, from inside the left slit's shadow (x = -2 in (-3, -1)) and close to the wall.
  const DoubleSlit slit(variant(1));
  const auto problem = double_slit_problem(variant(1));
  const int k = step_of(slit, 0.3);
  const auto mc = estimate_log_psi_monte_carlo(problem, Vec<1>(-2.0), k, 20000, {42});
  EXPECT_GT(mc.relative_se, 0.0);
  EXPECT_LT(mc.relative_se, 0.06);
  EXPECT_NEAR(mc.log_psi, slit.exact_log_psi(-2.0, slit.time(k)), 4.5 * mc.relative_se);
}

TEST(DoubleSlitGeneric, ControlAgreesWithTheExactControl) {
  // estimate_control reports no SE, so: R = 20 independent estimates (frozen-wall FD, M = 500);
  // their mean must be within 4.5 sd / sqrt(R) of the exact control, plus the O(1/M)
  // self-normalisation bias. That bias, measured with R = 200 at M = 100 on these points, is at
  // most 0.021 in size (|bias| M <= 2.1, and it shrinks as 1/M at M = 500): allow 2.5 / M.
  const int M = 500, R = 20;
  // Not x = 1.9: between the slits where both matter the FD quotient's sd is ~0.8 (the mixture
  // weights switch), too noisy for a sharp test.
  constexpr Point kControlPoints[] = {{0, 1.0, 0.0},  {0, 3.0, 0.3},  {0, -5.0, 0.5},
                                      {0, 10.0, 0.5}, {0, -2.0, 0.9}, {1, -2.0, 0.3},
                                      {1, 10.0, 0.51}};
  for (const auto& pt : kControlPoints) {
    const DoubleSlit slit(variant(pt.variant));
    const auto problem = double_slit_problem(variant(pt.variant));
    const int k = step_of(slit, pt.t);
    double s = 0.0, s2 = 0.0;
    for (int r = 0; r < R; ++r) {
      const auto c = estimate_control(problem, Vec<1>(pt.x), k, {.samples = M, .fd_step = 1e-3},
                                      {43, static_cast<std::uint64_t>(r)});
      ASSERT_TRUE(c.defined);
      s += c.u(0);
      s2 += c.u(0) * c.u(0);
    }
    const double mean = s / R, sd = std::sqrt((s2 - R * mean * mean) / (R - 1));
    EXPECT_GT(sd, 0.0);
    EXPECT_NEAR(mean, slit.exact_control(pt.x, slit.time(k)), 4.5 * sd / std::sqrt(R) + 2.5 / M)
        << "variant " << pt.variant << ", x = " << pt.x << ", k = " << k << ", sd " << sd;
  }
}

TEST(DoubleSlitGeneric, PathAtTheWallAndHorizonOnly) {
  // PathGrid::kWallsAndHorizon keeps y at t1 and tf only. Without drift and running cost the
  // increments in between integrate out exactly, so every estimate above holds for it too, and
  // after the wall (F quadratic, every weight 1) log psi_hat is the exact value on both grids.
  for (int v : {0, 1}) {
    const DoubleSlitParameters p = variant(v);
    const DoubleSlit slit(p);
    const auto fine = double_slit_problem(p);
    const auto coarse = double_slit_problem(p, PathGrid::kWallsAndHorizon);
    const int K = slit.num_steps(), K1 = slit.wall_step();
    EXPECT_EQ(coarse.path_length(0), 2);
    EXPECT_EQ(coarse.path_steps(0)[0], K1);
    EXPECT_EQ(coarse.path_steps(0)[1], K);
    EXPECT_EQ(coarse.path_length(K1 - 1), 2);
    EXPECT_EQ(coarse.path_length(K1), 1);
    EXPECT_EQ(coarse.block_at_step(3, K), 1);
    EXPECT_EQ(fine.path_length(3), K - 3);
    EXPECT_EQ(fine.block_at_step(3, K1), K1 - 4);
    for (int k : {K1 + 1, K1 + 3, K - 1}) {
      const double exact = slit.exact_log_psi(0.7, slit.time(k));
      for (const auto* problem : {&fine, &coarse}) {
        const auto e = estimate_log_psi_implicit(*problem, Vec<1>(0.7), k, 7, {3});
        EXPECT_NEAR(e.log_psi, exact, 1e-9 * (1.0 + std::abs(exact))) << "k = " << k;
        EXPECT_NEAR(e.log_psi_laplace, exact, 1e-9 * (1.0 + std::abs(exact))) << "k = " << k;
      }
    }
  }
  // Before the wall: the exact log psi within 4.5 SE (as LogPsiAgreesWithTheExactSolution), for
  // the mixture, the stratified modes and plain Monte Carlo.
  for (const auto& pt : kPoints) {
    const DoubleSlit slit(variant(pt.variant));
    const auto problem = double_slit_problem(variant(pt.variant), PathGrid::kWallsAndHorizon);
    const int k = step_of(slit, pt.t);
    const double exact = slit.exact_log_psi(pt.x, slit.time(k));
    for (auto map : {SamplingMap::kLinear, SamplingMap::kRandom}) {
      for (auto modes : {ModeSampling::kMixture, ModeSampling::kEachMode}) {
        const auto e = estimate_log_psi_implicit(problem, Vec<1>(pt.x), k, 4000, {44}, {}, {}, map,
                                                 nullptr, nullptr, {.modes = modes});
        EXPECT_EQ(e.map_failures, 0);
        EXPECT_GT(e.relative_se, 0.0);
        EXPECT_NEAR(e.log_psi, exact, 4.5 * e.relative_se)
            << "variant " << pt.variant << ", x = " << pt.x << ", k = " << k << ", "
            << to_string(map) << " map, modes " << static_cast<int>(modes);
      }
    }
  }
  const DoubleSlit slit(variant(1));
  const auto problem = double_slit_problem(variant(1), PathGrid::kWallsAndHorizon);
  const int k = step_of(slit, 0.3);
  const auto mc = estimate_log_psi_monte_carlo(problem, Vec<1>(-2.0), k, 20000, {42});
  EXPECT_LT(mc.relative_se, 0.06);
  EXPECT_NEAR(mc.log_psi, slit.exact_log_psi(-2.0, slit.time(k)), 4.5 * mc.relative_se);
}

TEST(DoubleSlitGeneric, StratifiedModesAreTheWallSpaceEstimator) {
  // ModeSampling::kEachMode with the frozen wall is estimator W2 (spec §2.4.4-2.4.5). Its control
  // at M = 50 has the mean and sd of the spec's table of point values over 20 000 repetitions,
  // O(1/M) bias included: the mean of R = 400 estimates must be within 4.5 sd / sqrt(R) of it.
  struct Reference {
    double x, t, mean, sd;
  };
  constexpr Reference kRefs[] = {
      {1.0, 0.0, -5.120, 0.040}, {-3.0, 0.5, -2.322, 0.075}, {-3.9, 0.98, -8.47, 0.57}};
  const DoubleSlit slit;
  const auto problem = double_slit_problem({}, PathGrid::kWallsAndHorizon);
  const int R = 400;
  for (const auto& ref : kRefs) {
    const int k = step_of(slit, ref.t);
    double s = 0.0;
    for (int r = 0; r < R; ++r) {
      const auto c =
          estimate_control(problem, Vec<1>(ref.x), k,
                           {.samples = 50, .fd_step = 1e-3, .modes = ModeSampling::kEachMode},
                           {45, static_cast<std::uint64_t>(r)});
      ASSERT_TRUE(c.defined);
      EXPECT_EQ(c.psi.samples, 100);  // 50 per slit
      s += c.u(0);
    }
    EXPECT_NEAR(s / R, ref.mean, 4.5 * ref.sd / std::sqrt(R))
        << "x = " << ref.x << ", t = " << ref.t;
  }
}

TEST(DoubleSlitGeneric, PaperEstimatorAimsAtTheEdge) {
  // The paper's P (dominant mode, Laplace weights) with the frozen wall: the pass count is the
  // same at x +- h, so u = sigma (e - x) / (t1 - t) exactly for any M (spec §2.4.5's table:
  // -5, -2 and -5 at these points, the edge of the dominant slit). Both grids.
  struct Reference {
    double x, t, u;
  };
  constexpr Reference kRefs[] = {{1.0, 0.0, -5.0}, {-3.0, 0.5, -2.0}, {-3.9, 0.98, -5.0}};
  const DoubleSlit slit;
  const EstimatorOptions paper{
      .samples = 10, .fd_step = 1e-3, .modes = ModeSampling::kDominant, .laplace_weights = true};
  for (auto grid : {PathGrid::kEveryStep, PathGrid::kWallsAndHorizon}) {
    const auto problem = double_slit_problem({}, grid);
    for (const auto& ref : kRefs) {
      const int k = step_of(slit, ref.t);
      for (std::uint64_t r = 0; r < 5; ++r) {
        const auto c = estimate_control(problem, Vec<1>(ref.x), k, paper, {46, r});
        ASSERT_TRUE(c.defined);
        EXPECT_EQ(c.psi.samples, 10);
        // All passing samples weigh the same: the ESS is the pass count.
        EXPECT_NEAR(c.psi.ess, c.psi.samples - c.psi.wall_hits, 1e-9);
        EXPECT_NEAR(c.u(0), ref.u, 1e-6) << "x = " << ref.x << ", t = " << ref.t;
      }
    }
  }
  const auto problem = double_slit_problem();
  EXPECT_THROW(estimate_control(problem, Vec<1>(1.0), 0,
                                {.samples = 5,
                                 .map = SamplingMap::kRandom,
                                 .modes = ModeSampling::kDominant,
                                 .laplace_weights = true},
                                {1}),
               implicit::InvalidArgument);
  EXPECT_THROW(
      estimate_control(problem, Vec<1>(1.0), 0, {.samples = 5, .laplace_weights = true}, {1}),
      implicit::InvalidArgument);
}

TEST(DoubleSlitGeneric, LaplaceFallbackWhenNoSamplePasses) {
  // One opening 1e-9 wide at x = 5: no sample passes, so log psi_hat = -inf. With the fallback
  // the control differentiates the Laplace mass of the frozen mode, sigma (e - x) / (t1 - t) =
  // 5 / 0.5 at t = 0.5; without it the control is undefined.
  ControlSpec<1, 1> s = double_slit_spec({}, PathGrid::kWallsAndHorizon);
  HardWall<1> narrow;
  narrow.time = 1.0;
  narrow.openings = {{5.0, 5.0 + 1e-9}};
  const DoubleSlitProblem problem(FreeWalkerModel{}, s, {narrow});
  const auto c = estimate_control(problem, Vec<1>(0.0), 25, {.samples = 20, .fd_step = 1e-3}, {7});
  EXPECT_FALSE(std::isfinite(c.psi.log_psi));
  EXPECT_TRUE(c.fallback);
  EXPECT_TRUE(c.defined);
  EXPECT_NEAR(c.u(0), 10.0, 1e-5);
  const auto none = estimate_control(
      problem, Vec<1>(0.0), 25, {.samples = 20, .fd_step = 1e-3, .laplace_fallback = false}, {7});
  EXPECT_FALSE(none.fallback);
  EXPECT_FALSE(none.defined);
  EXPECT_EQ(none.u(0), 0.0);
}

TEST(DoubleSlitGeneric, ControlAtTheWallIgnoresIt) {
  // At t1 the wall tests the current state, which u cannot move: log psi is -inf outside the
  // slits, but the control is that of t >= t1 (spec §2.4.6), -sigma x / (gamma + sigma (tf - t)).
  const DoubleSlit slit;
  const int K1 = slit.wall_step();
  for (auto grid : {PathGrid::kEveryStep, PathGrid::kWallsAndHorizon}) {
    const auto problem = double_slit_problem({}, grid);
    for (double x : {-3.0, 1.0, 7.0}) {
      const double l = estimate_log_psi_implicit(problem, Vec<1>(x), K1, 5, {2}).log_psi;
      if (slit.in_slits(x))
        EXPECT_NEAR(l, slit.exact_log_psi(x, 1.0), 1e-9 * (1.0 + std::abs(l)));
      else
        EXPECT_EQ(l, -INFINITY);
      for (auto method : {PsiMethod::kImplicit, PsiMethod::kMonteCarlo}) {
        const auto c = estimate_control(problem, Vec<1>(x), K1,
                                        {.samples = 5, .method = method, .fd_step = 1e-3}, {2});
        EXPECT_TRUE(c.defined);
        EXPECT_FALSE(c.fallback);
        if (method == PsiMethod::kImplicit)
          EXPECT_NEAR(c.u(0), slit.exact_control(x, 1.0), 1e-6) << "x = " << x;
        else
          EXPECT_TRUE(std::isfinite(c.u(0)));
      }
    }
  }
}

namespace {
// Declares itself linear-quadratic (inherited from FreeWalkerModel, with its zero drift and
// running cost), but its end cost is quartic.
struct WronglyDeclaredModel : FreeWalkerModel {
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 1, 1>& x) const {
    return 0.25 * x(0) * x(0) * x(0) * x(0);
  }
};
}  // namespace

TEST(DoubleSlitGeneric, AWrongLinearQuadraticDeclarationIsRefused) {
  // The wall-value sampler and the Laplace shortcut trust the declaration; a model whose F is
  // not quadratic must be refused, with walls ahead and without.
  const ControlSpec<1, 1> s = double_slit_spec({}, PathGrid::kWallsAndHorizon);
  const ControlProblem<1, 1, WronglyDeclaredModel> walled(WronglyDeclaredModel{}, s,
                                                          {double_slit_wall({})});
  EXPECT_THROW(
      estimate_log_psi_implicit(walled, Vec<1>(1.0), 0, 10, {1}, {}, {}, SamplingMap::kLinear,
                                nullptr, nullptr, {.modes = ModeSampling::kEachMode}),
      implicit::InvalidArgument);
  EXPECT_THROW(estimate_log_psi_implicit(walled, Vec<1>(1.0), 60, 10, {1}),
               implicit::InvalidArgument);
}
