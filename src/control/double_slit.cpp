#include "implicit/control/double_slit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/control/normal_tail.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/weights.hpp"

namespace implicit::control {

namespace {
// Central-difference step of the FD-CRN control (spec §2.4.5).
constexpr double kFdStep = 1e-3;

int grid_count(double t, double dt, const char* name) {
  const double r = t / dt;
  const double k = std::round(r);
  require(std::abs(r - k) <= 1e-9 * std::max(1.0, r) && k >= 1.0,
          "double slit: expected {} to be a positive multiple of dt, got {} / {} = {}", name, t, dt,
          r);
  return static_cast<int>(k);
}
}  // namespace

std::string_view to_string(SlitEstimator e) {
  switch (e) {
    case SlitEstimator::kPaper:
      return "paper";
    case SlitEstimator::kFrozenWall:
      return "corrected";
    case SlitEstimator::kPlainFd:
      return "plain";
  }
  return "unknown";
}

void check_double_slit_parameters(const DoubleSlitParameters& p) {
  require(std::isfinite(p.dt) && p.dt > 0.0, "double slit: expected dt > 0, got {}", p.dt);
  require(std::isfinite(p.sigma) && p.sigma > 0.0, "double slit: expected sigma > 0, got {}",
          p.sigma);
  require(std::isfinite(p.control_cost) && p.control_cost > 0.0,
          "double slit: expected control cost r > 0, got {}", p.control_cost);
  require(std::isfinite(p.wall_time) && std::isfinite(p.final_time) && p.wall_time > 0.0 &&
              p.wall_time < p.final_time,
          "double slit: expected 0 < t1 < tf, got t1 = {}, tf = {}", p.wall_time, p.final_time);
  for (int s = 0; s < 2; ++s)
    require(std::isfinite(p.slits[s].lower) && std::isfinite(p.slits[s].upper) &&
                p.slits[s].lower < p.slits[s].upper,
            "double slit: expected slit {} with lower < upper, got [{}, {}]", s, p.slits[s].lower,
            p.slits[s].upper);
  require(p.slits[0].upper < p.slits[1].lower,
          "double slit: expected disjoint slits in increasing order, got [{}, {}] and [{}, {}]",
          p.slits[0].lower, p.slits[0].upper, p.slits[1].lower, p.slits[1].upper);
  require(std::isfinite(p.initial_state), "double slit: expected a finite x(0), got {}",
          p.initial_state);
  // tf and t1 must be grid times (with 0 < t1 < tf above, t1 is then before tf on the grid).
  static_cast<void>(grid_count(p.final_time, p.dt, "tf"));
  static_cast<void>(grid_count(p.wall_time, p.dt, "t1"));
}

DoubleSlit::DoubleSlit(const DoubleSlitParameters& p) : p_(p) {
  check_double_slit_parameters(p);
  gamma_ = p.gamma();
  num_steps_ = grid_count(p.final_time, p.dt, "tf");
  wall_step_ = grid_count(p.wall_time, p.dt, "t1");
  factors_.resize(static_cast<std::size_t>(num_steps_));
  for (int k = 0; k < num_steps_; ++k) {
    const bool ok = factors_[static_cast<std::size_t>(k)].compute(path_hessian(k));
    require(ok, "double slit: the path Hessian at step {} is not positive definite", k);
  }
}

bool DoubleSlit::in_slits(double x) const {
  return p_.slits[0].contains(x) || p_.slits[1].contains(x);
}

void DoubleSlit::require_step(int k, const char* what) const {
  require(k >= 0 && k < num_steps_, "double slit {}: expected a grid step in [0, {}), got {}", what,
          num_steps_, k);
}

// ---- Exact solution ------------------------------------------------------------------------

double DoubleSlit::exact_log_psi(double x, double t) const {
  const double tf = p_.final_time, t1 = p_.wall_time, s = p_.sigma;
  require(std::isfinite(x), "double slit log psi: expected a finite state, got {}", x);
  require(t >= -1e-12 && t <= tf + 1e-12, "double slit log psi: expected a time in [0, {}], got {}",
          tf, t);
  const double spread = gamma_ + s * (tf - t);
  const double base = 0.5 * std::log(gamma_ / spread) - x * x / (2.0 * spread);
  const double eps = 1e-12 * std::max(1.0, t1);
  if (t > t1 + eps) return base;
  if (t >= t1 - eps) return in_slits(x) ? base : -kInfinity;
  const double v = s * (t1 - t), c = gamma_ + s * (tf - t1);
  const double m = x * c / (v + c), tau = std::sqrt(v * c / (v + c));
  std::array<double, 2> lp{};
  for (int i = 0; i < 2; ++i)
    lp[i] = log_normal_interval((p_.slits[i].lower - m) / tau, (p_.slits[i].upper - m) / tau);
  return base + log_sum_exp(lp);
}

double DoubleSlit::exact_control(double x, double t) const {
  const double tf = p_.final_time, t1 = p_.wall_time, s = p_.sigma;
  require(std::isfinite(x), "double slit control: expected a finite state, got {}", x);
  require(t >= -1e-12 && t <= tf + 1e-12, "double slit control: expected a time in [0, {}], got {}",
          tf, t);
  const double spread = gamma_ + s * (tf - t);
  // At and after t1 the wall no longer constrains the future: the unconstrained LQ control.
  if (t >= t1 - 1e-12 * std::max(1.0, t1)) return -s * x / spread;
  const double v = s * (t1 - t), c = gamma_ + s * (tf - t1);
  const double m = x * c / (v + c), tau = std::sqrt(v * c / (v + c));
  std::array<double, 2> lp{};
  std::array<double, 2> a{}, b{};
  for (int i = 0; i < 2; ++i) {
    a[i] = (p_.slits[i].lower - m) / tau;
    b[i] = (p_.slits[i].upper - m) / tau;
    lp[i] = log_normal_interval(a[i], b[i]);
  }
  const double log_s = log_sum_exp(lp);
  // (phi(a) - phi(b)) / S in log space: each ratio is O(|a|) even when S underflows.
  double sum = 0.0;
  for (int i = 0; i < 2; ++i)
    sum += std::exp(log_normal_pdf(a[i]) - log_s) - std::exp(log_normal_pdf(b[i]) - log_s);
  return s * (-x / spread + (c / (v + c)) * sum / tau);
}

// ---- Discretised path problem --------------------------------------------------------------

double DoubleSlit::tau2(int k) const {
  const double v = p_.sigma * (wall_step_ - k) * p_.dt;
  const double c = gamma_ + p_.sigma * (num_steps_ - wall_step_) * p_.dt;
  return v * c / (v + c);
}

double DoubleSlit::mean_at_wall(double x, int k) const {
  const double v = p_.sigma * (wall_step_ - k) * p_.dt;
  const double c = gamma_ + p_.sigma * (num_steps_ - wall_step_) * p_.dt;
  return x * c / (v + c);
}

SlitMinimum DoubleSlit::frozen_minimum(double x, int k, double edge) const {
  require(k >= 0 && k < wall_step_,
          "double slit constrained minimum: expected a step before the wall, in [0, {}), got {}",
          wall_step_, k);
  const double v = p_.sigma * (wall_step_ - k) * p_.dt;
  const double c = gamma_ + p_.sigma * (num_steps_ - wall_step_) * p_.dt;
  SlitMinimum r;
  r.edge = edge;
  r.phi = (edge - x) * (edge - x) / (2.0 * v) + edge * edge / (2.0 * c);
  r.nu = (edge - x) / v + edge / c;
  return r;
}

SlitMinimum DoubleSlit::constrained_minimum(double x, int k, int s) const {
  require(s == 0 || s == 1, "double slit: expected slit 0 or 1, got {}", s);
  const double m = mean_at_wall(x, k);
  const Slit& sl = p_.slits[static_cast<std::size_t>(s)];
  SlitMinimum r = frozen_minimum(x, k, std::clamp(m, sl.lower, sl.upper));
  r.active = m < sl.lower || m > sl.upper;
  if (!r.active) r.nu = 0.0;  // exactly zero at an interior minimum (avoids rounding noise)
  return r;
}

Eigen::VectorXd DoubleSlit::minimizer_path(double x, int k, double edge) const {
  require_step(k, "minimiser path");
  const int n = num_steps_ - k;
  const double s = p_.sigma, dt = p_.dt;
  Eigen::VectorXd mu(n);
  if (k >= wall_step_) {
    for (int i = 1; i <= n; ++i)
      mu(i - 1) = x * (gamma_ + s * (n - i) * dt) / (gamma_ + s * n * dt);
    return mu;
  }
  const int w = wall_step_ - k;
  for (int i = 1; i <= n; ++i)
    mu(i - 1) = i <= w ? x + (edge - x) * static_cast<double>(i) / w
                       : edge * (gamma_ + s * (n - i) * dt) / (gamma_ + s * (n - w) * dt);
  return mu;
}

double DoubleSlit::path_function(double x, const Eigen::VectorXd& y) const {
  const double inv = 1.0 / (2.0 * p_.sigma * p_.dt);
  double f = 0.0, prev = x;
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    const double d = y(i) - prev;
    f += d * d * inv;
    prev = y(i);
  }
  return f + prev * prev / (2.0 * gamma_);
}

BlockTridiagonal<1> DoubleSlit::path_hessian(int k) const {
  require_step(k, "path Hessian");
  const int n = num_steps_ - k;
  const double a = 1.0 / (p_.sigma * p_.dt);
  BlockTridiagonal<1> h(n);
  for (int i = 0; i < n; ++i) h.diagonal[i](0, 0) = 2.0 * a;
  h.diagonal[n - 1](0, 0) = a + 1.0 / gamma_;
  for (int i = 0; i + 1 < n; ++i) h.subdiagonal[i](0, 0) = -a;
  return h;
}

double DoubleSlit::log_normalizer(int k) const {
  require_step(k, "normaliser");
  const int n = num_steps_ - k;
  return 0.5 * n * std::log(p_.sigma * p_.dt) + factors_[static_cast<std::size_t>(k)].log_det_L();
}

// ---- Estimators ----------------------------------------------------------------------------

void DoubleSlit::path_weights(double x, int k, int s, double edge, const Eigen::MatrixXd& xi,
                              std::vector<double>& log_w, std::vector<double>* delta,
                              Eigen::MatrixXd* paths) const {
  const int n = num_steps_ - k;
  require(xi.rows() == n,
          "double slit path sampler: expected reference variables of length {}, "
          "got {}",
          n, xi.rows());
  const auto& chol = factors_[static_cast<std::size_t>(k)];
  const Eigen::VectorXd mu = minimizer_path(x, k, edge);
  // psi = Z / (2 pi sigma dt)^{n/2}: the implicit weights of exp(-F) over the path measure's
  // normaliser.
  const double log_path_norm = gaussian_log_normaliser(n, 0.5 * n * std::log(p_.sigma * p_.dt));
  const int M = static_cast<int>(xi.cols());
  log_w.resize(static_cast<std::size_t>(M));
  if (delta) delta->resize(static_cast<std::size_t>(M));
  if (paths) paths->resize(n, M);
  const bool walled = k < wall_step_;
  const int w = wall_step_ - k;
  Eigen::VectorXd y(n);
  for (int j = 0; j < M; ++j) {
    y = xi.col(j);
    chol.upper_solve_in_place(y);  // L^{-T} xi
    if (walled && delta) (*delta)[static_cast<std::size_t>(j)] = y(w - 1);
    y += mu;
    if (paths) paths->col(j) = y;
    const bool pass = !walled || p_.slits[static_cast<std::size_t>(s)].contains(y(w - 1));
    log_w[static_cast<std::size_t>(j)] =
        pass ? implicit_log_weight(n, xi.col(j).squaredNorm(), path_function(x, y),
                                   chol.log_det_L()) -
                   log_path_norm
             : -kInfinity;
  }
}

double DoubleSlit::combine(const std::vector<double>& lw0, const std::vector<double>& lw1, int M,
                           SlitEstimator estimator, int dominant, double phi_dominant,
                           int k) const {
  if (estimator == SlitEstimator::kPaper) {
    const auto& lw = dominant == 0 ? lw0 : lw1;
    int pass = 0;
    for (double l : lw) pass += std::isfinite(l) ? 1 : 0;
    if (pass == 0) return -kInfinity;
    return -phi_dominant - log_normalizer(k) + std::log(static_cast<double>(pass) / M);
  }
  // W2: psi_hat = sum over slits of the mean weight of that slit's M samples.
  const double l0 = log_sum_exp(lw0), l1 = log_sum_exp(lw1);
  const std::array<double, 2> both{l0, l1};
  return log_sum_exp(both) - std::log(static_cast<double>(M));
}

double DoubleSlit::log_psi_from_offsets(double x, int k, std::span<const double> delta0,
                                        std::span<const double> delta1,
                                        SlitEstimator estimator) const {
  require(k >= 0 && k < wall_step_, "double slit estimator: expected a step in [0, {}), got {}",
          wall_step_, k);
  require(delta0.size() == delta1.size() && !delta0.empty(),
          "double slit estimator: expected equal non-empty offset arrays, got {} and {}",
          delta0.size(), delta1.size());
  const double log_norm = log_normalizer(k);
  std::array<SlitMinimum, 2> mins{constrained_minimum(x, k, 0), constrained_minimum(x, k, 1)};
  std::array<std::vector<double>, 2> lw;
  for (int s = 0; s < 2; ++s) {
    const auto& d = s == 0 ? delta0 : delta1;
    lw[s].resize(d.size());
    for (std::size_t j = 0; j < d.size(); ++j)
      lw[s][j] = p_.slits[s].contains(mins[s].edge + d[j])
                     ? -log_norm - mins[s].phi - mins[s].nu * d[j]
                     : -kInfinity;
  }
  const int dom = mins[0].phi <= mins[1].phi ? 0 : 1;
  return combine(lw[0], lw[1], static_cast<int>(delta0.size()), estimator, dom, mins[dom].phi, k);
}

SlitControlEstimate DoubleSlit::estimate_control(double x, int k, int M, SlitEstimator estimator,
                                                 const StreamKey& key,
                                                 SlitSampling sampling) const {
  require_step(k, "control estimate");
  require(M >= 1, "double slit control estimate: expected at least 1 sample, got {}", M);
  require(std::isfinite(x), "double slit control estimate: expected a finite state, got {}", x);
  const int n = num_steps_ - k;
  Rng rng({key.seed, key.step, key.index, purpose::kReference});
  SlitControlEstimate out;
  const double h = kFdStep;

  if (k >= wall_step_) {
    // After the wall F is quadratic: every weight is 1 and psi_hat is exact for any M.
    out.samples = M;
    out.passed = M;
    out.ess = M;
    const double spread = gamma_ + p_.sigma * n * p_.dt;
    out.log_psi = 0.5 * std::log(gamma_ / spread) - x * x / (2.0 * spread);
    if (sampling == SlitSampling::kWall) {
      out.u = -p_.sigma * x / spread;
      return out;
    }
    Eigen::MatrixXd xi(n, M);
    rng.fill_normal(xi);
    std::vector<double> lp, lm;
    path_weights(x + h, k, 0, 0.0, xi, lp, nullptr, nullptr);
    path_weights(x - h, k, 0, 0.0, xi, lm, nullptr, nullptr);
    out.u = p_.sigma * (log_mean_exp(lp) - log_mean_exp(lm)) / (2.0 * h);
    return out;
  }

  const std::array<SlitMinimum, 2> at_x{constrained_minimum(x, k, 0), constrained_minimum(x, k, 1)};
  const int dom = at_x[0].phi <= at_x[1].phi ? 0 : 1;
  const bool frozen = estimator == SlitEstimator::kFrozenWall;
  const double log_norm = log_normalizer(k);

  // Log weights of both slits' samples at a perturbed state x', with the SAME reference
  // variables (common random numbers).
  std::array<std::vector<double>, 2> lw_p, lw_m, lw_0;
  std::array<std::vector<double>, 2> delta;
  auto minimum_at = [&](double xp, int s) {
    return frozen ? frozen_minimum(xp, k, at_x[s].edge) : constrained_minimum(xp, k, s);
  };
  if (sampling == SlitSampling::kWall) {
    const double tau = std::sqrt(tau2(k));
    for (int s = 0; s < 2; ++s) {
      delta[s].resize(static_cast<std::size_t>(M));
      for (auto& d : delta[s]) d = tau * rng.normal();
    }
    auto weights = [&](double xp, std::array<std::vector<double>, 2>& lw) {
      for (int s = 0; s < 2; ++s) {
        const SlitMinimum mn = minimum_at(xp, s);
        lw[s].resize(static_cast<std::size_t>(M));
        for (int j = 0; j < M; ++j) {
          const double d = delta[s][static_cast<std::size_t>(j)];
          lw[s][static_cast<std::size_t>(j)] =
              p_.slits[s].contains(mn.edge + d) ? -log_norm - mn.phi - mn.nu * d : -kInfinity;
        }
      }
    };
    weights(x, lw_0);
    weights(x + h, lw_p);
    weights(x - h, lw_m);
  } else {
    std::array<Eigen::MatrixXd, 2> xi{Eigen::MatrixXd(n, M), Eigen::MatrixXd(n, M)};
    rng.fill_normal(xi[0]);
    rng.fill_normal(xi[1]);
    for (int s = 0; s < 2; ++s) {
      path_weights(x, k, s, at_x[s].edge, xi[s], lw_0[s], nullptr, nullptr);
      path_weights(x + h, k, s, minimum_at(x + h, s).edge, xi[s], lw_p[s], nullptr, nullptr);
      path_weights(x - h, k, s, minimum_at(x - h, s).edge, xi[s], lw_m[s], nullptr, nullptr);
    }
  }

  const double l0 = combine(lw_0[0], lw_0[1], M, estimator, dom, at_x[dom].phi, k);
  const double lp = combine(lw_p[0], lw_p[1], M, estimator, dom, minimum_at(x + h, dom).phi, k);
  const double lm = combine(lw_m[0], lw_m[1], M, estimator, dom, minimum_at(x - h, dom).phi, k);
  out.log_psi = l0;
  out.samples = estimator == SlitEstimator::kPaper ? M : 2 * M;
  // ESS and pass counts over the samples the estimator uses.
  double sw = 0.0, sw2 = 0.0, lmax = -kInfinity;
  for (int s = 0; s < 2; ++s) {
    if (estimator == SlitEstimator::kPaper && s != dom) continue;
    for (double l : lw_0[s]) {
      if (std::isfinite(l)) ++out.passed;
      lmax = std::max(lmax, l);
    }
  }
  if (estimator == SlitEstimator::kPaper) {
    out.ess = out.passed;
  } else if (std::isfinite(lmax)) {
    for (int s = 0; s < 2; ++s)
      for (double l : lw_0[s]) {
        const double w = std::exp(l - lmax);
        sw += w;
        sw2 += w * w;
      }
    out.ess = sw * sw / sw2;
  }
  if (std::isfinite(lp) && std::isfinite(lm)) {
    out.u = p_.sigma * (lp - lm) / (2.0 * h);
  } else {
    // No sample passed: aim at the dominant slit's edge (the Laplace control).
    out.fallback = true;
    out.u = (at_x[dom].edge - x) / ((wall_step_ - k) * p_.dt);
  }
  return out;
}

double DoubleSlit::frozen_wall_limit(double x, int k, int M, const StreamKey& key,
                                     SlitSampling sampling) const {
  require(k >= 0 && k < wall_step_,
          "double slit frozen-wall limit: expected a step in [0, {}), "
          "got {}",
          wall_step_, k);
  require(M >= 1, "double slit frozen-wall limit: expected at least 1 sample, got {}", M);
  const int n = num_steps_ - k;
  Rng rng({key.seed, key.step, key.index, purpose::kReference});
  std::array<std::vector<double>, 2> lw, delta;
  const std::array<SlitMinimum, 2> mins{constrained_minimum(x, k, 0), constrained_minimum(x, k, 1)};
  if (sampling == SlitSampling::kWall) {
    const double tau = std::sqrt(tau2(k));
    for (int s = 0; s < 2; ++s) {
      delta[s].resize(static_cast<std::size_t>(M));
      for (auto& d : delta[s]) d = tau * rng.normal();
    }
    for (int s = 0; s < 2; ++s) {
      lw[s].resize(static_cast<std::size_t>(M));
      for (int j = 0; j < M; ++j) {
        const double d = delta[s][static_cast<std::size_t>(j)];
        lw[s][static_cast<std::size_t>(j)] =
            p_.slits[s].contains(mins[s].edge + d) ? -mins[s].phi - mins[s].nu * d : -kInfinity;
      }
    }
  } else {
    std::array<Eigen::MatrixXd, 2> xi{Eigen::MatrixXd(n, M), Eigen::MatrixXd(n, M)};
    rng.fill_normal(xi[0]);
    rng.fill_normal(xi[1]);
    for (int s = 0; s < 2; ++s)
      path_weights(x, k, s, mins[s].edge, xi[s], lw[s], &delta[s], nullptr);
  }
  double lmax = -kInfinity;
  for (int s = 0; s < 2; ++s)
    for (double l : lw[s]) lmax = std::max(lmax, l);
  require(std::isfinite(lmax), "double slit frozen-wall limit: no sample passed a slit");
  double sw = 0.0, swy = 0.0;
  for (int s = 0; s < 2; ++s)
    for (int j = 0; j < M; ++j) {
      const double w = std::exp(lw[s][static_cast<std::size_t>(j)] - lmax);
      sw += w;
      swy += w * (mins[s].edge + delta[s][static_cast<std::size_t>(j)]);
    }
  return (swy / sw - x) / ((wall_step_ - k) * p_.dt);
}

std::vector<double> DoubleSlit::path_log_weights(double x, int k, int s, const Eigen::MatrixXd& xi,
                                                 std::vector<double>* delta,
                                                 Eigen::MatrixXd* paths) const {
  require_step(k, "path sampler");
  require(s == 0 || s == 1, "double slit: expected slit 0 or 1, got {}", s);
  const double edge = k < wall_step_ ? constrained_minimum(x, k, s).edge : 0.0;
  std::vector<double> lw;
  path_weights(x, k, s, edge, xi, lw, delta, paths);
  return lw;
}

PlainMonteCarloResult DoubleSlit::plain_monte_carlo(double x, int k, int paths, std::uint64_t seed,
                                                    std::uint64_t step, Eigen::MatrixXd* kept,
                                                    int keep) const {
  require_step(k, "plain Monte Carlo");
  require(paths >= 1, "double slit plain Monte Carlo: expected at least 1 path, got {}", paths);
  const int n = num_steps_ - k;
  keep = std::clamp(keep, 0, paths);
  if (kept) kept->resize(n + 1, keep);
  std::vector<double> log_w(static_cast<std::size_t>(paths));
  const double sd = std::sqrt(p_.sigma * p_.dt);
  const int w = wall_step_ - k;
  parallel_for(static_cast<std::size_t>(paths), [&](std::size_t j) {
    Rng rng({seed, step, j, purpose::kProposal});
    double y = x;
    bool pass = true;
    const bool store = kept && static_cast<int>(j) < keep;
    if (store) (*kept)(0, static_cast<Eigen::Index>(j)) = y;
    for (int i = 1; i <= n; ++i) {
      y += sd * rng.normal();
      if (i == w && !in_slits(y)) pass = false;
      if (store) (*kept)(i, static_cast<Eigen::Index>(j)) = y;
    }
    log_w[j] = pass ? -y * y / (2.0 * gamma_) : -kInfinity;
  });
  PlainMonteCarloResult r;
  r.paths = paths;
  for (double l : log_w) r.passed += std::isfinite(l) ? 1 : 0;
  r.log_psi = log_mean_exp(log_w);
  return r;
}

// ---- Closed loop ---------------------------------------------------------------------------

SlitRun simulate_slit_run(const DoubleSlit& slit, int samples, SlitEstimator estimator,
                          std::uint64_t seed, std::uint64_t run, SlitSampling sampling,
                          const Eigen::VectorXd& noise) {
  const auto& p = slit.parameters();
  const int K = slit.num_steps(), K1 = slit.wall_step();
  Eigen::VectorXd W = noise;
  if (W.size() == 0) {
    W.resize(K);
    Rng rng({seed, run, 0, purpose::kProcessNoise});
    rng.fill_normal(W);
  }
  require(W.size() == K, "double slit closed loop: expected {} noise values, got {}", K, W.size());
  SlitRun r;
  r.x_exact.resize(K + 1);
  r.x_estimate.resize(K + 1);
  r.u_exact.resize(K);
  r.u_estimate.resize(K);
  r.x_exact(0) = r.x_estimate(0) = p.initial_state;
  const double sd = std::sqrt(p.sigma * p.dt);
  double ess_sum = 0.0;
  for (int k = 0; k < K; ++k) {
    const double t = slit.time(k);
    r.u_exact(k) = slit.exact_control(r.x_exact(k), t);
    if (k < K1) {
      const auto e = slit.estimate_control(r.x_estimate(k), k, samples, estimator,
                                           {seed, run, static_cast<std::uint64_t>(k), 0}, sampling);
      r.u_estimate(k) = e.u;
      r.fallbacks += e.fallback ? 1 : 0;
      ess_sum += e.ess;
    } else {
      r.u_estimate(k) = -p.sigma * r.x_estimate(k) / (slit.gamma() + p.sigma * (p.final_time - t));
    }
    r.x_exact(k + 1) = r.x_exact(k) + r.u_exact(k) * p.dt + sd * W(k);
    r.x_estimate(k + 1) = r.x_estimate(k) + r.u_estimate(k) * p.dt + sd * W(k);
  }
  score_slit_run(slit, r);
  r.ess_mean = ess_sum / K1;
  return r;
}

void score_slit_run(const DoubleSlit& slit, SlitRun& r) {
  const int K1 = slit.wall_step();
  r.crashed_exact = !slit.in_slits(r.x_exact(K1));
  r.crashed_estimate = !slit.in_slits(r.x_estimate(K1));
  r.error_x = (r.x_estimate - r.x_exact).norm() / r.x_exact.norm();
  r.error_u = (r.u_estimate - r.u_exact).norm() / r.u_exact.norm();
}

}  // namespace implicit::control
