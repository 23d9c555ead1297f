// The generic path integral control problem and estimators (spec §2.1-2.3).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "implicit/control/double_slit.hpp"
#include "implicit/control/himmelblau.hpp"
#include "implicit/control/path_integral.hpp"
#include "implicit/core/error.hpp"

using namespace implicit::control;
using implicit::Mat;
using implicit::Vec;

namespace {

// Ornstein-Uhlenbeck drift, quadratic running and final costs: F is quadratic.
struct LinearQuadratic {
  template <typename T>
  Eigen::Matrix<T, 1, 1> drift(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return -1.0 * x;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return 0.5 * x(0) * x(0);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 1, 1>& x) const {
    return 1.5 * (x(0) - 1.0) * (x(0) - 1.0);
  }
};

ControlSpec<1, 1> scalar_spec(double sigma, double r, double horizon, double dt) {
  ControlSpec<1, 1> s;
  s.G << 1.0;
  s.noise_covariance << sigma;
  s.control_cost << r;
  s.horizon = horizon;
  s.dt = dt;
  return s;
}

}  // namespace

TEST(ControlSpec, ConditionEightAndBadInput) {
  EXPECT_NEAR(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.02)), 0.1, 1e-15);
  // Two controls: R = diag(1, 2) with Q Q^T = I violates (8) (gamma would differ per axis).
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.control_cost << 1, 0, 0, 2;
  try {
    check_control_spec(s);
    FAIL() << "expected InvalidArgument";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("condition (8)"), std::string::npos) << e.what();
  }
  s.control_cost.setIdentity();
  s.noise_covariance << 1, 0, 0, -1;  // not positive semi-definite
  EXPECT_THROW(check_control_spec(s), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.0)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, -0.1)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, 0.1, 2.0, 0.03)), implicit::InvalidArgument);
  EXPECT_THROW(check_control_spec(scalar_spec(1.0, -0.1, 2.0, 0.02)), implicit::InvalidArgument);
  // Partial noise (noise on the velocity only): Sigma singular, a clear error.
  ControlSpec<2, 1> arm;
  arm.G << 0, 1;
  arm.noise_covariance << 1;
  arm.control_cost << 0.01;
  try {
    check_control_spec(arm);
    FAIL() << "expected InvalidArgument";
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
}

TEST(PathIntegral, ExactForQuadraticFAnyM) {
  // After the double slit's wall: log psi = 1/2 log(g/(g + s n dt)) - x^2/(2(g + s n dt)).
  ControlProblem problem(FreeWalkerModel{}, scalar_spec(1.0, 0.1, 1.0, 0.02));
  for (int M : {1, 7}) {
    for (int k : {0, 30, 49}) {
      const Vec<1> x(0.7);
      const auto e = estimate_log_psi_implicit(problem, x, k, M, {5});
      const double spread = 0.1 + (50 - k) * 0.02;
      EXPECT_NEAR(e.log_psi, 0.5 * std::log(0.1 / spread) - 0.49 / (2 * spread), 1e-10);
      EXPECT_NEAR(e.ess, M, 1e-9);
      const auto c = estimate_control(problem, x, k, {.samples = M}, {5});
      EXPECT_NEAR(c.u(0), -0.7 / spread, 1e-7);
    }
  }
}

TEST(PathIntegral, BandedHessianMatchesFiniteDifferences) {
  ControlProblem problem(LinearQuadratic{}, scalar_spec(0.5, 2.0, 1.0, 0.1));
  const auto F = problem.path_function(Vec<1>(0.3), 0);
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(10, -0.5, 0.8), g, gp, gm;
  implicit::BlockTridiagonal<1> H;
  F.evaluate(y, &g, &H);
  const Eigen::MatrixXd Hd = H.to_dense();
  for (int i = 0; i < 10; ++i) {
    Eigen::VectorXd yp = y, ym = y;
    yp(i) += 1e-6;
    ym(i) -= 1e-6;
    EXPECT_NEAR(g(i), (F.evaluate(yp, nullptr, nullptr) - F.evaluate(ym, nullptr, nullptr)) / 2e-6,
                1e-6 * (1 + std::abs(g(i))));
    F.evaluate(yp, &gp, nullptr);
    F.evaluate(ym, &gm, nullptr);
    const Eigen::VectorXd col = (gp - gm) / 2e-6;
    EXPECT_LT((col - Hd.col(i)).cwiseAbs().maxCoeff(), 1e-6 * (1 + Hd.cwiseAbs().maxCoeff()));
  }
}

TEST(PathIntegral, ImplicitAgreesWithPlainMonteCarlo) {
  // F is quadratic (linear drift, quadratic costs), so implicit sampling is exact (equal
  // weights); plain Monte Carlo is unbiased for psi. Tolerance: 4.5 SE of log psi_hat_MC, the
  // SE taken from its weights (relative sd / sqrt(M)).
  ControlProblem problem(LinearQuadratic{}, scalar_spec(0.5, 2.0, 1.0, 0.05));
  EXPECT_NEAR(problem.gamma(), 1.0, 1e-15);
  const Vec<1> x(0.4);
  const auto imp = estimate_log_psi_implicit(problem, x, 0, 20, {9});
  EXPECT_NEAR(imp.ess, 20.0, 1e-9);
  const auto mc = estimate_log_psi_monte_carlo(problem, x, 0, 20000, {9});
  EXPECT_NEAR(mc.log_psi, imp.log_psi, 4.5 * mc.relative_se);
  EXPECT_GT(mc.relative_se, 0.0);
}

TEST(PathIntegral, HimmelblauThroughTheGenericProblem) {
  // From the drift path (no warm start), the generic estimator reaches Table 4's first control,
  // which himmelblau_control finds from its straight-line start (himmelblau_test.cpp).
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.noise_covariance = 0.01 * Mat<2>::Identity();
  s.control_cost = 0.01 * Mat<2>::Identity();
  s.horizon = 20.0;
  s.dt = 1.0;
  ControlProblem problem(HimmelblauModel{}, s);
  EXPECT_NEAR(problem.gamma(), 1e-4, 1e-18);
  const Vec<2> x0(-1, -4);
  const auto c = estimate_control(problem, x0, 0, {.samples = 50}, {3});
  ASSERT_EQ(c.worst_status, implicit::MinimizeStatus::kConverged);
  EXPECT_NEAR(c.u(0), -0.1389649, 1e-6);
  EXPECT_NEAR(c.u(1), 0.0358407, 1e-6);
  EXPECT_NEAR(c.psi.minimizer(38), -3.77929836, 1e-7);
  EXPECT_NEAR(c.psi.minimizer(39), -3.28318625, 1e-7);
  EXPECT_GT(c.psi.ess, 45.0);
}

TEST(PathIntegral, ClosedLoopTakesTheNoiseAsInput) {
  ControlProblem problem(FreeWalkerModel{}, scalar_spec(1.0, 0.1, 1.0, 0.02));
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(1, 50);
  const auto r = simulate_closed_loop(problem, Vec<1>(1.0), zero, {.samples = 3}, 1);
  ASSERT_EQ(r.x.size(), 51u);
  // Noise-free LQ: x_{k+1} = x_k (1 - dt/(g + s (tf - t_k))).
  double x = 1.0;
  for (int k = 0; k < 50; ++k) x *= 1.0 - 0.02 / (0.1 + (50 - k) * 0.02);
  EXPECT_NEAR(r.x.back()(0), x, 1e-7);
  EXPECT_THROW(simulate_closed_loop(problem, Vec<1>(1.0), Eigen::MatrixXd::Zero(1, 3), {}, 1),
               implicit::InvalidArgument);
  // A warm start for another horizon is an error, not silently replaced by the drift path.
  EXPECT_THROW(estimate_log_psi_implicit(problem, Vec<1>(1.0), 0, 3, {1}, Eigen::VectorXd(49)),
               implicit::InvalidArgument);
  EXPECT_THROW(estimate_control(problem, Vec<1>(1.0), 1, {.samples = 3}, {1}, Eigen::VectorXd(50)),
               implicit::InvalidArgument);
}

namespace {

// Convex but not quadratic: linear drift, quartic running and final costs. F is convex in the
// path, so the random map is one-to-one (star-shaped F) and both maps are exact samplers.
struct QuarticCosts {
  template <typename T>
  Eigen::Matrix<T, 1, 1> drift(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return -0.5 * x;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 1, 1>& x, double) const {
    return 0.5 * x(0) * x(0) + 0.25 * x(0) * x(0) * x(0) * x(0);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 1, 1>& x) const {
    const T d = x(0) - 1.0;
    return 0.5 * d * d + 0.5 * d * d * d * d;
  }
};

std::vector<HardWall<1>> slit_walls() {
  return {HardWall<1>{.time = 1.0, .openings = {{-6.0, -4.0}, {6.0, 8.0}}}};
}

// The double slit's exact log psi (spec §2.4.1) at t = 0, for the cross-check.
double slit_exact_log_psi(double x) {
  const double g = 0.1, v = 1.0, c = g + 1.0, tf = 2.0;
  const double m = x * c / (v + c), tau = std::sqrt(v * c / (v + c));
  auto cdf = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  const double S =
      cdf((-4 - m) / tau) - cdf((-6 - m) / tau) + cdf((8 - m) / tau) - cdf((6 - m) / tau);
  return 0.5 * std::log(g / (g + tf)) - x * x / (2 * (g + tf)) + std::log(S);
}

}  // namespace

TEST(PathIntegral, RandomMapExactForQuadraticF) {
  // F quadratic: the random map's root is lambda = sqrt(rho) and its Jacobian 1 for every xi,
  // so each weight equals psi exactly; both maps give the closed form to rounding.
  ControlProblem problem(LinearQuadratic{}, scalar_spec(0.5, 2.0, 1.0, 0.05));
  for (int k : {0, 11, 19}) {
    const Vec<1> x(0.4);
    const auto lin = estimate_log_psi_implicit(problem, x, k, 5, {4});
    const auto rnd = estimate_log_psi_implicit(problem, x, k, 5, {4}, {}, {}, SamplingMap::kRandom);
    EXPECT_NEAR(rnd.log_psi, lin.log_psi, 1e-9) << "k = " << k;
    EXPECT_NEAR(rnd.ess, 5.0, 1e-9);
    EXPECT_EQ(rnd.map_failures, 0);
    EXPECT_EQ(rnd.wall_hits, 0);
  }
  // After the double slit's wall (closed form in ExactForQuadraticFAnyM), through the control.
  ControlProblem walker(FreeWalkerModel{}, scalar_spec(1.0, 0.1, 1.0, 0.02));
  const auto c =
      estimate_control(walker, Vec<1>(0.7), 10, {.samples = 3, .map = SamplingMap::kRandom}, {5});
  EXPECT_NEAR(c.u(0), -0.7 / (0.1 + 40 * 0.02), 1e-7);
}

TEST(PathIntegral, RandomAndLinearMapAgreeOnANonQuadraticProblem) {
  // Tolerances: the two implicit estimates use different seeds (independent), so their difference
  // has SE sqrt(se_l^2 + se_r^2), with se = relative sd of the weights / sqrt(M) (the delta-method
  // SE of log psi_hat); plain MC with 2e5 paths is the reference, checked against each within
  // 4.5 of the combined SE.
  ControlProblem problem(QuarticCosts{}, scalar_spec(0.5, 1.0, 1.0, 0.05));
  const Vec<1> x(-0.3);
  const auto lin = estimate_log_psi_implicit(problem, x, 0, 4000, {21});
  const auto rnd =
      estimate_log_psi_implicit(problem, x, 0, 4000, {22}, {}, {}, SamplingMap::kRandom);
  ASSERT_EQ(rnd.map_failures, 0);
  ASSERT_GT(lin.relative_se, 0.0);
  ASSERT_GT(rnd.relative_se, 0.0);
  // The weights really vary (else the test could not fail for a wrong Jacobian).
  EXPECT_LT(rnd.ess, 3999.0);
  EXPECT_NEAR(rnd.log_psi, lin.log_psi, 4.5 * std::hypot(lin.relative_se, rnd.relative_se));
  const auto mc = estimate_log_psi_monte_carlo(problem, x, 0, 200000, {23});
  EXPECT_NEAR(lin.log_psi, mc.log_psi, 4.5 * std::hypot(lin.relative_se, mc.relative_se));
  EXPECT_NEAR(rnd.log_psi, mc.log_psi, 4.5 * std::hypot(rnd.relative_se, mc.relative_se));
}

TEST(PathIntegral, HardWallMixtureReproducesTheDoubleSlit) {
  // Spec §2.4.1 / §2.4.3: the discretisation is exact at grid times, so E[psi_hat] = psi_exact.
  // Tolerance: 4.5 SE of log psi_hat (relative sd of the weights / sqrt(M)).
  ControlProblem problem(FreeWalkerModel{}, scalar_spec(1.0, 0.1, 2.0, 0.02), slit_walls());
  EXPECT_NEAR(slit_exact_log_psi(1.0), -24.070635, 1e-6);  // spec §2.4.2 table
  for (double x : {1.0, 1.9}) {  // left slit dominates; both slits matter (switch at 1.909)
    const auto e = estimate_log_psi_implicit(problem, Vec<1>(x), 0, 10000, {31});
    ASSERT_EQ(e.modes.size(), 2u);
    EXPECT_EQ(e.status, implicit::MinimizeStatus::kConverged);
    EXPECT_NEAR(e.log_psi, slit_exact_log_psi(x), 4.5 * e.relative_se) << "x = " << x;
    EXPECT_LT(e.relative_se, 0.05);
    // Constrained minima on the slit edges nearest to m = 11 x / 21 (spec §2.4.3).
    EXPECT_EQ(e.modes[0].clamped[0], 1);
    EXPECT_EQ(e.modes[1].clamped[0], -1);
    EXPECT_NEAR(e.modes[0].wall_values[0], -4.0, 1e-9);
    EXPECT_NEAR(e.modes[1].wall_values[0], 6.0, 1e-9);
    // phi_s of spec §2.4.3 at x = 1: 19.772727 and 28.863636.
    if (x == 1.0) {
      EXPECT_NEAR(e.modes[0].phi, 19.7727272727, 1e-8);
      EXPECT_NEAR(e.modes[1].phi, 28.8636363636, 1e-8);
    }
    // About half of each component's samples hit the wall (centred on an edge, spec E32).
    EXPECT_GT(e.wall_hits, 3000);
    EXPECT_LT(e.wall_hits, 7000);
    EXPECT_EQ(e.modes[0].samples + e.modes[1].samples, 10000);
    // The random map inside each mode's opening (F is convex: exact), weights divided by pi_c.
    const auto r =
        estimate_log_psi_implicit(problem, Vec<1>(x), 0, 10000, {34}, {}, {}, SamplingMap::kRandom);
    EXPECT_EQ(r.map_failures, 0);
    EXPECT_NEAR(r.log_psi, slit_exact_log_psi(x), 4.5 * r.relative_se) << "x = " << x;
    EXPECT_LT(r.relative_se, 0.05);
  }
  // Between the openings both modes carry weight; plain MC cannot pass the wall there.
  const auto both = estimate_log_psi_implicit(problem, Vec<1>(1.9), 0, 1000, {32});
  EXPECT_GT(std::exp(both.modes[0].log_weight), 0.2);
  EXPECT_GT(std::exp(both.modes[1].log_weight), 0.2);
  const auto mc = estimate_log_psi_monte_carlo(problem, Vec<1>(1.9), 0, 20000, {33});
  EXPECT_GT(mc.wall_hits, 19990);
}

TEST(PathIntegral, HardWallControlMatchesTheDoubleSlit) {
  // Frozen-wall FD-CRN control at (1, 0), M = 200, R = 40 independent evaluations: the mean
  // must be within 4.5 sd / sqrt(R) of the exact -5.109548, plus the O(1/M) self-normalisation
  // bias (spec §2.4.5 measures +0.011 at M = 50 for W2, i.e. 0.003 at M = 200; allow 0.01).
  ControlProblem problem(FreeWalkerModel{}, scalar_spec(1.0, 0.1, 2.0, 0.02), slit_walls());
  const int R = 40;
  double s = 0.0, s2 = 0.0;
  for (int r = 0; r < R; ++r) {
    const auto c = estimate_control(problem, Vec<1>(1.0), 0, {.samples = 200, .fd_step = 1e-3},
                                    {100, static_cast<std::uint64_t>(r)});
    ASSERT_TRUE(c.defined);
    s += c.u(0);
    s2 += c.u(0) * c.u(0);
  }
  const double mean = s / R, sd = std::sqrt((s2 - R * mean * mean) / (R - 1));
  EXPECT_GT(sd, 0.0);
  EXPECT_NEAR(mean, -5.109548, 4.5 * sd / std::sqrt(R) + 0.01) << "sd " << sd;
  // At the wall time a state outside the openings has psi = 0; after it the wall is behind.
  const auto at_wall = estimate_log_psi_implicit(problem, Vec<1>(0.0), 50, 5, {1});
  EXPECT_EQ(at_wall.log_psi, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(at_wall.wall_hits, 5);
  const auto behind = estimate_log_psi_implicit(problem, Vec<1>(0.0), 51, 5, {1});
  EXPECT_TRUE(std::isfinite(behind.log_psi));
  EXPECT_TRUE(behind.modes.empty());
}

TEST(PathIntegral, HardWallBadInput) {
  const auto spec = scalar_spec(1.0, 0.1, 2.0, 0.02);
  auto make = [&](HardWall<1> w) { ControlProblem p(FreeWalkerModel{}, spec, {w}); };
  EXPECT_THROW(make({.time = 1.01, .openings = {{0, 1}}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 0.0, .openings = {{0, 1}}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 2.02, .openings = {{0, 1}}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 1.0, .openings = {}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 1.0, .openings = {{1, 0}}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 1.0, .openings = {{0, 2}, {1, 3}}}), implicit::InvalidArgument);
  EXPECT_THROW(make({.time = 1.0, .direction = Vec<1>(0.0), .openings = {{0, 1}}}),
               implicit::InvalidArgument);
  try {
    make({.time = 1.0, .openings = {{0, 2}, {1, 3}}});
  } catch (const implicit::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("opening 1"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(make({.time = 2.0, .openings = {{-1, 1}}}));
}

namespace {
// A planar free walker (G = I, Sigma = 0.5 I) pulled towards (1, 0) by its final cost.
struct PlanarWalker {
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return x * 0.0;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double) const {
    return 0.1 * x(0) * x(0);
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    const T a = x(0) - 1.0, b = x(1);
    return 0.5 * (a * a + b * b);
  }
};
}  // namespace

TEST(PathIntegral, TwoWallsInThePlaneAgreeWithPlainMonteCarlo) {
  // Two walls (an oblique one at t = 0.5, an axis one at t = 1) with two openings each: four
  // modes, some with both walls clamped. Plain MC can pass these openings, so it is an
  // independent reference; tolerance 4.5 times the combined delta-method SE of the two
  // independent estimates.
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.noise_covariance = 0.5 * Mat<2>::Identity();
  s.control_cost = 2.0 * Mat<2>::Identity();
  s.horizon = 1.5;
  s.dt = 0.05;
  const Vec<2> diagonal = Vec<2>(1.0, 1.0).normalized();
  std::vector<HardWall<2>> walls{
      {.time = 0.5, .direction = diagonal, .openings = {{-1.2, -0.6}, {0.3, 0.5}}},
      {.time = 1.0, .direction = Vec<2>(0.0, 1.0), .openings = {{-2.0, -0.4}, {0.6, 2.0}}}};
  ControlProblem problem(PlanarWalker{}, s, walls);
  const Vec<2> x(0.1, -0.2);
  const auto e = estimate_log_psi_implicit(problem, x, 0, 20000, {41});
  ASSERT_EQ(e.modes.size(), 4u);
  int clamped_twice = 0;
  for (const auto& m : e.modes) {
    EXPECT_EQ(m.status, implicit::MinimizeStatus::kConverged);
    clamped_twice += (m.clamped[0] != 0 && m.clamped[1] != 0) ? 1 : 0;
    // Every mode's centre lies in (or on the edge of) its openings.
    for (int i = 0; i < 2; ++i) {
      const auto& op = walls[i].openings[static_cast<std::size_t>(m.openings[i])];
      EXPECT_GE(m.wall_values[i], op.lower - 1e-9);
      EXPECT_LE(m.wall_values[i], op.upper + 1e-9);
    }
  }
  EXPECT_GE(clamped_twice, 1);
  const auto mc = estimate_log_psi_monte_carlo(problem, x, 0, 400000, {42});
  ASSERT_LT(mc.wall_hits, 400000);
  EXPECT_NEAR(e.log_psi, mc.log_psi, 4.5 * std::hypot(e.relative_se, mc.relative_se))
      << "SE implicit " << e.relative_se << ", MC " << mc.relative_se;
  const auto r =
      estimate_log_psi_implicit(problem, x, 0, 20000, {44}, {}, {}, SamplingMap::kRandom);
  EXPECT_EQ(r.map_failures, 0);
  EXPECT_NEAR(r.log_psi, mc.log_psi, 4.5 * std::hypot(r.relative_se, mc.relative_se))
      << "SE random map " << r.relative_se << ", MC " << mc.relative_se;
  // The same key gives the same estimate (common random numbers for the control).
  const auto again = estimate_log_psi_implicit(problem, x, 0, 20000, {41});
  EXPECT_EQ(again.log_psi, e.log_psi);
  const auto c = estimate_control(problem, x, 0, {.samples = 200}, {43});
  EXPECT_TRUE(c.defined);
  EXPECT_TRUE(c.u.allFinite());
}

namespace {
// A planar robot pushed by wind along +x past a Gaussian bump at (1, 0) (non-convex F).
struct BumpRobot {
  template <typename T>
  Eigen::Matrix<T, 2, 1> drift(const Eigen::Matrix<T, 2, 1>& x, double) const {
    Eigen::Matrix<T, 2, 1> w;
    w << x(0) * 0.0 + 0.3, x(1) * 0.0;
    return w;
  }
  template <typename T>
  T running_cost(const Eigen::Matrix<T, 2, 1>& x, double) const {
    using std::exp;
    const T dx = x(0) - 1.0, dy = x(1);
    return 20.0 * exp(-(dx * dx + dy * dy) / (2.0 * 0.09));
  }
  template <typename T>
  T final_cost(const Eigen::Matrix<T, 2, 1>& x) const {
    const T dx = x(0) - 2.0, dy = x(1);
    return 5.0 * (dx * dx + dy * dy);
  }
};
}  // namespace

TEST(PathIntegral, HardWallModesPassAnObstacleOnTheirOwnSide) {
  // A gate at t = 0.5 with openings below and above the bump's axis. Clamping only the gate
  // point of the free minimiser (which passes above) leaves the lower mode's path going back
  // over the bump (a local minimum, F = 51.0 instead of 32.9); the translated start fixes it.
  // Mirror symmetry is the oracle: mode "below" from y0 = 0.05 equals mode "above" from -0.05.
  ControlSpec<2, 2> s;
  s.G.setIdentity();
  s.noise_covariance = 0.05 * Mat<2>::Identity();
  s.control_cost = 2.0 * Mat<2>::Identity();
  s.horizon = 2.0;
  s.dt = 0.05;
  ControlProblem problem(
      BumpRobot{}, s,
      {HardWall<2>{
          .time = 0.5, .direction = Vec<2>(0, 1), .openings = {{-0.6, -0.3}, {0.3, 0.6}}}});
  const auto up = estimate_log_psi_implicit(problem, Vec<2>(0.0, 0.05), 0, 10, {1});
  const auto down = estimate_log_psi_implicit(problem, Vec<2>(0.0, -0.05), 0, 10, {1});
  ASSERT_EQ(up.modes.size(), 2u);
  for (int m = 0; m < 2; ++m) {
    EXPECT_EQ(up.modes[m].status, implicit::MinimizeStatus::kConverged);
    EXPECT_NEAR(up.modes[m].phi, down.modes[1 - m].phi, 1e-6 * up.modes[m].phi);
    // At t = 1 (block 20, x about 1) the path is on its opening's side of the bump.
    const double y_at_bump = up.modes[m].minimizer(2 * 19 + 1);
    EXPECT_LT(m == 0 ? y_at_bump : -y_at_bump, -0.3) << "mode " << m;
  }
}
