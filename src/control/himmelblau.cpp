#include "implicit/control/himmelblau.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "implicit/control/controller.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/target.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::control {

double himmelblau(const Vec<2>& x, Vec<2>* grad, Mat<2>* hess) {
  const double a = x(0) * x(0) + x(1) - 11.0;
  const double b = x(0) + x(1) * x(1) - 7.0;
  if (grad) *grad << 4.0 * x(0) * a + 2.0 * b, 2.0 * a + 4.0 * x(1) * b;
  if (hess)
    *hess << 4.0 * a + 8.0 * x(0) * x(0) + 2.0, 4.0 * (x(0) + x(1)), 4.0 * (x(0) + x(1)),
        2.0 + 4.0 * b + 8.0 * x(1) * x(1);
  return a * a + b * b;
}

std::vector<Vec<2>> himmelblau_newton(const Vec<2>& x0, int iterations) {
  require(iterations >= 0, "Himmelblau Newton: expected iterations >= 0, got {}", iterations);
  std::vector<Vec<2>> xs{x0};
  Vec<2> g;
  Mat<2> h;
  for (int i = 0; i < iterations; ++i) {
    const Vec<2>& x = xs.back();
    himmelblau(x, &g, &h);
    // Full Newton steps, as the paper: H may be indefinite (the iteration is attracted by the
    // saddle), so use a pivoted LU solve rather than Cholesky.
    xs.push_back(x - h.fullPivLu().solve(g));
  }
  return xs;
}

int HimmelblauProblem::num_steps() const {
  require(std::isfinite(dt) && dt > 0.0, "Himmelblau problem: expected dt > 0, got {}", dt);
  const double r = final_time / dt;
  const double n = std::round(r);
  require(std::isfinite(r) && std::abs(r - n) <= 1e-9 * std::max(1.0, r) && n >= 1.0,
          "Himmelblau problem: expected tf to be a positive multiple of dt, got tf / dt = {}", r);
  return static_cast<int>(n);
}

void HimmelblauProblem::validate() const {
  require(std::isfinite(control_cost) && control_cost > 0.0,
          "Himmelblau problem: expected R > 0, got {}", control_cost);
  require(std::isfinite(sigma) && sigma > 0.0, "Himmelblau problem: expected sigma > 0, got {}",
          sigma);
  require(x0.allFinite(), "Himmelblau problem: expected a finite start point");
  (void)num_steps();
}

Eigen::VectorXd HimmelblauLaplace::path() const {
  Eigen::VectorXd mu(2 * n);
  for (int i = 1; i <= n; ++i)
    mu.segment<2>(2 * (i - 1)) = x + (end - x) * (static_cast<double>(i) / n);
  return mu;
}

HimmelblauLaplace himmelblau_laplace(const HimmelblauProblem& pb, const Vec<2>& x, int k,
                                     const Vec<2>& warm) {
  const int K = pb.num_steps();
  require(k >= 0 && k < K, "Himmelblau: expected a step in [0, {}), got {}", K, k);
  require(x.allFinite() && warm.allFinite(), "Himmelblau: expected a finite state and start");
  const int n = K - k;
  const double g = pb.gamma(), spread = pb.sigma * n * pb.dt;
  auto reduced = make_analytic_target<2>([&](const Vec<2>& z, Vec<2>* grad, Mat<2>* hess) {
    Vec<2> gf;
    Mat<2> hf;
    const double f = himmelblau(z, grad ? &gf : nullptr, hess ? &hf : nullptr);
    if (grad) *grad = (z - x) / spread + gf / g;
    if (hess) *hess = Mat<2>::Identity() / spread + hf / g;
    return (z - x).squaredNorm() / (2.0 * spread) + f / g;
  });
  const auto r = minimize(reduced, warm);
  HimmelblauLaplace lp;
  lp.x = x;
  lp.end = r.x;
  lp.phi = r.value;
  lp.n = n;
  lp.status = r.status;
  // Hessian of F at mu: (T kron I2) / (sigma dt) plus grad^2 f(z*) / gamma in the last block.
  Mat<2> hf;
  himmelblau(lp.end, nullptr, &hf);
  const double w = 1.0 / (pb.sigma * pb.dt);
  BlockTridiagonal<2> H(n);
  for (int i = 0; i < n; ++i) H.diagonal[i] = 2.0 * w * Mat<2>::Identity();
  for (int i = 0; i + 1 < n; ++i) H.subdiagonal[i] = -w * Mat<2>::Identity();
  H.diagonal[n - 1] = w * Mat<2>::Identity() + hf / g;
  double damping = 0.0;
  while (!lp.factor.compute(H)) {
    // Not SPD (the minimiser stopped at a saddle): any SPD Hessian keeps the weights exact.
    const double add = damping == 0.0 ? 1e-8 * H.diagonal[n - 1].cwiseAbs().maxCoeff() : damping;
    H.diagonal[n - 1].diagonal().array() += add;
    damping = 10.0 * add;
    if (lp.status == MinimizeStatus::kConverged) lp.status = MinimizeStatus::kNotPositiveDefinite;
  }
  lp.log_det_L = lp.factor.log_det_L();
  return lp;
}

double himmelblau_path_function(const HimmelblauProblem& pb, const Vec<2>& x,
                                const Eigen::VectorXd& y) {
  const int n = static_cast<int>(y.size() / 2);
  const double inv = 1.0 / (2.0 * pb.sigma * pb.dt);
  double f = 0.0;
  Vec<2> prev = x;
  for (int i = 0; i < n; ++i) {
    const Vec<2> yi = y.segment<2>(2 * i);
    f += (yi - prev).squaredNorm() * inv;
    prev = yi;
  }
  return f + himmelblau(prev) / pb.gamma();
}

HimmelblauControlProblem himmelblau_control_problem(const HimmelblauProblem& pb) {
  pb.validate();
  ControlSpec<2, 2> spec;
  spec.G.setIdentity();
  spec.noise_covariance = pb.sigma * Mat<2>::Identity();
  spec.control_cost = pb.control_cost * Mat<2>::Identity();
  spec.horizon = pb.final_time;
  spec.dt = pb.dt;
  return HimmelblauControlProblem(HimmelblauModel{}, spec);
}

HimmelblauEstimate himmelblau_control(const HimmelblauControlProblem& problem, const Vec<2>& x,
                                      int k, int M, const Vec<2>& warm, const StreamKey& key) {
  const int K = problem.num_steps();
  require(k >= 0 && k < K, "Himmelblau control: expected a step in [0, {}), got {}", K, k);
  require(M >= 1, "Himmelblau control: expected at least 1 sample, got {}", M);
  require(x.allFinite() && warm.allFinite(),
          "Himmelblau control: expected a finite state and start");
  const int n = K - k;
  Eigen::VectorXd start(2 * n);
  for (int i = 1; i <= n; ++i) start.segment<2>(2 * (i - 1)) = x + (warm - x) * (double(i) / n);
  const auto c = estimate_control(problem, x, k, {.samples = M, .fd_step = 1e-4}, key, start);
  HimmelblauEstimate est;
  est.u = c.u;
  est.log_psi = c.psi.log_psi;
  est.ess = c.psi.ess;
  est.end = c.psi.minimizer.tail<2>();
  est.laplace_u = (est.end - x) / (n * problem.dt());
  est.status = c.worst_status;
  return est;
}

HimmelblauEstimate himmelblau_control(const HimmelblauProblem& pb, const Vec<2>& x, int k, int M,
                                      const Vec<2>& warm, const StreamKey& key) {
  return himmelblau_control(himmelblau_control_problem(pb), x, k, M, warm, key);
}

HimmelblauRun simulate_himmelblau_run(const HimmelblauProblem& pb, int M, std::uint64_t seed,
                                      std::uint64_t run) {
  const auto problem = himmelblau_control_problem(pb);
  const int K = pb.num_steps();
  Rng noise({seed, run, 0, purpose::kProcessNoise});
  HimmelblauRun r;
  r.x.push_back(pb.x0);
  Vec<2> warm = pb.x0;
  const double sd = std::sqrt(pb.sigma * pb.dt);
  for (int k = 0; k < K; ++k) {
    const auto est = himmelblau_control(problem, r.x.back(), k, M, warm,
                                        {seed, run, static_cast<std::uint64_t>(k), 0});
    warm = est.end;
    r.ess_mean += est.ess / K;
    r.failed_minimizations += est.status == MinimizeStatus::kConverged ? 0 : 1;
    r.u.push_back(est.u);
    r.max_laplace_gap = std::max(r.max_laplace_gap, (est.u - est.laplace_u).cwiseAbs().maxCoeff());
    r.cost += 0.5 * pb.control_cost * est.u.squaredNorm() * pb.dt;
    const Vec<2> w = noise.normal_vector<2>();
    r.x.push_back(r.x.back() + est.u * pb.dt + sd * w);
    r.last_noise = w;
  }
  r.final_f = himmelblau(r.x.back());
  r.cost += r.final_f;
  return r;
}

namespace {
// E g(m + sqrt(v) W), W ~ N(0, I2), by the 5-point Gauss-Hermite rule (probabilists' weight):
// exact for polynomials of degree <= 9 in each coordinate, so for f (degree 4) and f^2 (degree 8).
template <typename Fn>
double gaussian_expectation(const Vec<2>& m, double v, Fn&& g) {
  const double a = std::sqrt(5.0 - std::sqrt(10.0)), b = std::sqrt(5.0 + std::sqrt(10.0));
  const double nodes[5] = {-b, -a, 0.0, a, b};
  const double weights[5] = {
      (7.0 - 2.0 * std::sqrt(10.0)) / 60.0, (7.0 + 2.0 * std::sqrt(10.0)) / 60.0, 8.0 / 15.0,
      (7.0 + 2.0 * std::sqrt(10.0)) / 60.0, (7.0 - 2.0 * std::sqrt(10.0)) / 60.0};
  const double s = std::sqrt(v);
  double e = 0.0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      e += weights[i] * weights[j] * g(Vec<2>(m(0) + s * nodes[i], m(1) + s * nodes[j]));
  return e;
}
}  // namespace

HimmelblauBridgeReference himmelblau_bridge_reference(const HimmelblauProblem& pb) {
  pb.validate();
  const int K = pb.num_steps();
  HimmelblauBridgeReference ref;
  // The runs are steered towards z*(x0) from the first step on; x* is the minimum of f there.
  const Vec<2> start = himmelblau_laplace(pb, pb.x0, 0, pb.x0).end;
  auto f = make_analytic_target<2>(
      [](const Vec<2>& x, Vec<2>* g, Mat<2>* h) { return himmelblau(x, g, h); });
  ref.minimizer = minimize(f, start).x;
  const Vec<2> e0 = pb.x0 - ref.minimizer;
  const double s2 = pb.sigma * pb.dt;  // variance of one noise increment per coordinate
  // E|u_k dt|^2 = |e0|^2/K^2 + 2 s2 sum_{j<k} 1/n_{j+1}^2, with n_{j+1} = K - j - 1.
  double accumulated = 0.0;  // sum_{j<k} 1/n_{j+1}^2
  for (int k = 0; k < K; ++k) {
    ref.control_cost +=
        0.5 * pb.control_cost / pb.dt * (e0.squaredNorm() / (K * K) + 2.0 * s2 * accumulated);
    const double n_next = K - k - 1;
    if (n_next > 0) accumulated += 1.0 / (n_next * n_next);
  }
  auto f_only = [](const Vec<2>& x) { return himmelblau(x); };
  auto f_squared = [](const Vec<2>& x) { return std::pow(himmelblau(x), 2); };
  ref.final_f = gaussian_expectation(ref.minimizer, s2, f_only);
  ref.final_f_sd = std::sqrt(std::max(
      0.0, gaussian_expectation(ref.minimizer, s2, f_squared) - ref.final_f * ref.final_f));
  // x_{K-1} = x* + e0/K + sqrt(s2) sum_{j<K-1} W_j / n_{j+1}: variance s2 sum_{i=1}^{K-1} 1/i^2.
  const Vec<2> m = ref.minimizer + e0 / K;
  const double v = s2 * accumulated;
  ref.f_before_last_step = gaussian_expectation(m, v, f_only);
  ref.f_before_last_step_sd =
      std::sqrt(std::max(0.0, gaussian_expectation(m, v, f_squared) -
                                  ref.f_before_last_step * ref.f_before_last_step));
  return ref;
}

double last_step_adjusted_cost(const HimmelblauProblem& pb, const HimmelblauRun& run,
                               const HimmelblauBridgeReference& ref) {
  const Vec<2> end = ref.minimizer + std::sqrt(pb.sigma * pb.dt) * run.last_noise;
  return run.cost - himmelblau(end) + ref.final_f;
}

}  // namespace implicit::control
