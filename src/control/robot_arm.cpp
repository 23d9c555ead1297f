#include "implicit/control/robot_arm.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>

#include <Eigen/Cholesky>

#include "implicit/control/controller.hpp"
#include "implicit/core/banded.hpp"
#include "implicit/core/error.hpp"

namespace implicit::control {

void ArmParameters::validate() const {
  for (double v : {l1, lc1, lc2, m1, m2, I1, I2})
    require(std::isfinite(v) && v > 0.0,
            "arm parameters: expected positive lengths, masses and inertias, got l1 = {}, lc1 = "
            "{}, lc2 = {}, m1 = {}, m2 = {}, I1 = {}, I2 = {}",
            l1, lc1, lc2, m1, m2, I1, I2);
}

Mat<2> arm_mass_matrix(const ArmParameters& p, const Vec<2>& theta) {
  const double c2 = std::cos(theta(1));
  Mat<2> m;
  m << p.a1() + 2.0 * p.a3() * c2, p.a2() + p.a3() * c2, p.a2() + p.a3() * c2, p.a2();
  return m;
}

Mat<2> arm_coriolis_matrix(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot) {
  const double h = p.a3() * std::sin(theta(1));
  Mat<2> c;
  c << -h * theta_dot(1), -h * (theta_dot(0) + theta_dot(1)), h * theta_dot(0), 0.0;
  return c;
}

Vec<2> arm_inverse_dynamics(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot,
                            const Vec<2>& u) {
  return arm_mass_matrix(p, theta) * u + arm_coriolis_matrix(p, theta, theta_dot) * theta_dot;
}

Vec<2> arm_acceleration(const ArmParameters& p, const Vec<2>& theta, const Vec<2>& theta_dot,
                        const Vec<2>& tau) {
  const Eigen::LLT<Mat<2>> llt(arm_mass_matrix(p, theta));
  return llt.solve(tau - arm_coriolis_matrix(p, theta, theta_dot) * theta_dot);
}

Vec<4> arm_rk4_step(const ArmParameters& p, const Vec<4>& s, const Vec<2>& tau, double h) {
  auto f = [&](const Vec<4>& x) {
    Vec<4> d;
    d.head<2>() = x.tail<2>();
    d.tail<2>() = arm_acceleration(p, x.head<2>(), x.tail<2>(), tau);
    return d;
  };
  const Vec<4> k1 = f(s);
  const Vec<4> k2 = f(s + 0.5 * h * k1);
  const Vec<4> k3 = f(s + 0.5 * h * k2);
  const Vec<4> k4 = f(s + h * k3);
  return s + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

int ArmProblem::num_steps() const {
  require(std::isfinite(dt) && dt > 0.0, "arm problem: expected dt > 0, got {}", dt);
  require(std::isfinite(final_time) && final_time > 0.0,
          "arm problem: expected a final time > 0, got {}", final_time);
  const double r = final_time / dt;
  const double n = std::round(r);
  require(std::abs(r - n) <= 1e-9 * r && n >= 1.0,
          "arm problem: expected tf to be a multiple of dt, got tf / dt = {}", r);
  return static_cast<int>(n);
}

void ArmProblem::validate() const {
  require(std::isfinite(control_cost) && control_cost > 0.0,
          "arm problem: expected a control cost r > 0, got {}", control_cost);
  require(std::isfinite(sigma) && sigma > 0.0,
          "arm problem: expected a velocity noise variance sigma > 0, got {}", sigma);
  require(target.allFinite() && initial_state.allFinite(),
          "arm problem: expected a finite target and initial state");
  (void)num_steps();
}

JointPathIntegral joint_path_integral(double z0, double y0, double target, int n,
                                      const ArmProblem& problem) {
  require(n >= 1, "arm path integral: expected at least 1 step to go, got {}", n);
  const double dt = problem.dt, s = problem.sigma, g = problem.gamma();
  const bool explicit_scheme = problem.scheme == ArmScheme::kExplicit;
  // z_n = c0 + a^T y: the final angle is a deterministic linear function of the velocity path.
  Eigen::VectorXd a = Eigen::VectorXd::Constant(n, dt);
  double c0 = z0;
  if (explicit_scheme) {
    a(n - 1) = 0.0;
    c0 += dt * y0;
  }
  // F(y) = 1/2 y^T (Hb + a a^T / gamma) y - b^T y + const.
  BlockTridiagonal<1> hb(n);
  const double w = 1.0 / (s * dt);
  for (int i = 0; i < n; ++i) hb.diagonal[i](0, 0) = 2.0 * w;
  hb.diagonal[n - 1](0, 0) = w + 1.0 / g;
  for (int i = 0; i + 1 < n; ++i) hb.subdiagonal[i](0, 0) = -w;
  BlockTridiagonalCholesky<1> chol;
  require(chol.compute(hb), "arm path integral: the path Hessian is not positive definite");
  Eigen::VectorXd b = -(c0 - target) / g * a;
  b(0) += y0 * w;
  const Eigen::VectorXd hb_b = chol.solve(b), hb_a = chol.solve(a);
  const double sa = a.dot(hb_a);
  JointPathIntegral r;
  // Sherman-Morrison: (Hb + a a^T/g)^{-1} b = Hb^{-1} b - Hb^{-1} a (a^T Hb^{-1} b) / (g + a^T
  // Hb^{-1} a).
  r.mu = hb_b - hb_a * (a.dot(hb_b) / (g + sa));
  // Matrix determinant lemma: det(Hb + a a^T/g) = det Hb (1 + a^T Hb^{-1} a / g).
  r.log_det_L = chol.log_det_L() + 0.5 * std::log1p(sa / g);
  double f = 0.0, prev = y0;
  for (int i = 0; i < n; ++i) {
    f += 0.5 * w * (r.mu(i) - prev) * (r.mu(i) - prev);
    prev = r.mu(i);
  }
  r.final_angle = c0 + a.dot(r.mu);
  f += (prev * prev + (r.final_angle - target) * (r.final_angle - target)) / (2.0 * g);
  r.phi = f;
  r.log_psi = -r.phi - 0.5 * n * std::log(s * dt) - r.log_det_L;
  // u = -sigma dphi/dy0 (envelope theorem: only the explicit y0-dependence of F counts).
  r.u = (r.mu(0) - y0) / dt;
  if (explicit_scheme) r.u -= s * dt * (r.final_angle - target) / g;
  return r;
}

Vec<2> arm_path_integral_control(const Vec<4>& x, int n, const ArmProblem& problem) {
  Vec<2> u;
  for (int j = 0; j < 2; ++j)
    u(j) = joint_path_integral(x(j), x(2 + j), problem.target(j), n, problem).u;
  return u;
}

JointRiccati joint_riccati(double target, int n, const ArmProblem& problem) {
  require(n >= 1, "arm Riccati recursion: expected at least 1 step, got {}", n);
  const double dt = problem.dt, r = problem.control_cost;
  Mat<2> A;
  A << 1.0, dt, 0.0, 1.0;
  Vec<2> B(problem.scheme == ArmScheme::kExplicit ? 0.0 : dt * dt, dt);
  JointRiccati ric;
  ric.P.resize(static_cast<std::size_t>(n + 1));
  ric.q.resize(static_cast<std::size_t>(n + 1));
  ric.K.resize(static_cast<std::size_t>(n));
  ric.k.resize(static_cast<std::size_t>(n));
  ric.P[n] = Mat<2>::Identity();
  ric.q[n] = Vec<2>(-target, 0.0);
  for (int i = n - 1; i >= 0; --i) {
    const Mat<2>& P = ric.P[i + 1];
    const Vec<2>& q = ric.q[i + 1];
    const double S = r * dt + B.dot(P * B);
    ric.K[i] = (B.transpose() * P * A) / S;
    ric.k[i] = B.dot(q) / S;
    const Mat<2> closed = A - B * ric.K[i];
    ric.P[i] = A.transpose() * P * closed;
    ric.P[i] = 0.5 * (ric.P[i] + ric.P[i].transpose()).eval();  // keep it exactly symmetric
    ric.q[i] = closed.transpose() * q;
  }
  return ric;
}

ArmJointProblem arm_joint_problem(const ArmProblem& problem, int joint) {
  problem.validate();
  require(joint == 0 || joint == 1, "arm joint problem: expected joint 0 or 1, got {}", joint);
  require(problem.scheme == ArmScheme::kExplicit,
          "arm joint problem: the generic problem integrates the angle by forward Euler (the "
          "explicit scheme); the semi-implicit scheme needs the closed form");
  ControlSpec<2, 1> spec;
  spec.G << 0.0, 1.0;
  spec.noise_covariance(0, 0) = problem.sigma;
  spec.control_cost(0, 0) = problem.control_cost;
  spec.horizon = problem.num_steps() * problem.dt;  // an exact multiple of dt
  spec.dt = problem.dt;
  return ArmJointProblem(ArmJointModel{problem.target(joint)}, spec);
}

namespace {
// Both joints' controls from the generic estimator: F is quadratic, so the estimate is the
// Laplace value (no sampling) and u its central difference along the velocity.
class GenericArmControl {
 public:
  explicit GenericArmControl(const ArmProblem& p)
      : joints_{arm_joint_problem(p, 0), arm_joint_problem(p, 1)} {
    options_.samples = 1;
  }
  Vec<2> operator()(const Vec<4>& x, int k) const {
    Vec<2> u;
    for (int j = 0; j < 2; ++j) {
      const auto& pj = joints_[static_cast<std::size_t>(j)];
      const auto c =
          estimate_control(pj, Vec<2>(x(j), x(2 + j)), k, options_,
                           {0, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(j), 0});
      require(c.defined, "arm simulation: the generic estimator gave no control at step {}", k);
      u(j) = c.u(0);
    }
    return u;
  }

 private:
  std::array<ArmJointProblem, 2> joints_;
  EstimatorOptions options_;
};
}  // namespace

ArmSimulation simulate_arm(const ArmProblem& problem, const ArmParameters& plant,
                           const ArmParameters& model, int substeps, ArmController controller) {
  problem.validate();
  plant.validate();
  model.validate();
  require(substeps >= 1, "arm simulation: expected at least 1 RK4 substep, got {}", substeps);
  std::optional<GenericArmControl> generic;
  if (controller == ArmController::kGeneric) generic.emplace(problem);
  const int K = problem.num_steps();
  const double dt = problem.dt, r = problem.control_cost;
  std::array<JointRiccati, 2> ric{joint_riccati(problem.target(0), K, problem),
                                  joint_riccati(problem.target(1), K, problem)};
  ArmSimulation sim;
  sim.t.resize(static_cast<std::size_t>(K + 1));
  sim.x.resize(static_cast<std::size_t>(K + 1));
  sim.u.resize(static_cast<std::size_t>(K));
  sim.tau.resize(static_cast<std::size_t>(K));
  sim.x[0] = problem.initial_state;
  for (int k = 0; k <= K; ++k) sim.t[k] = k * dt;
  for (int k = 0; k < K; ++k) {
    const Vec<4>& x = sim.x[k];
    const Vec<2> u = generic ? (*generic)(x, k) : arm_path_integral_control(x, K - k, problem);
    for (int j = 0; j < 2; ++j) {
      const Vec<2> xj(x(j), x(2 + j));
      // Explicit scheme: u_PI = -(1/r) dV0/dy; semi-implicit: u_PI = first LQR control.
      const double lqr = problem.scheme == ArmScheme::kExplicit
                             ? -(ric[j].P[k] * xj + ric[j].q[k])(1) / r
                             : ric[j].control(k, xj);
      sim.lqr_max_abs_diff = std::max(sim.lqr_max_abs_diff, std::abs(u(j) - lqr));
    }
    sim.u[k] = u;
    sim.tau[k] = arm_inverse_dynamics(model, x.head<2>(), x.tail<2>(), u);
    Vec<4> s = x;
    for (int i = 0; i < substeps; ++i) s = arm_rk4_step(plant, s, sim.tau[k], dt / substeps);
    sim.x[k + 1] = s;
  }
  sim.final_angle_error = (sim.x[K].head<2>() - problem.target).norm();
  return sim;
}

}  // namespace implicit::control
