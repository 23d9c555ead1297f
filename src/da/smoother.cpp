#include "implicit/da/smoother.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/log_weight.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"

namespace implicit::da {
namespace {

double log_det_lower(const Eigen::MatrixXd& lower) { return lower.diagonal().array().log().sum(); }

/// The lower Cholesky factor of `cov`, with filters.hpp's ridge when the members collapsed onto
/// a subspace; a non-finite covariance is refused in the smoother's words.
void factor_background(const Eigen::MatrixXd& cov, Eigen::MatrixXd& lower) {
  require(cov.allFinite(),
          "implicit smoother: the background covariance of the members is not finite");
  covariance_factor(cov, lower);
}

/// Newton on a window's F: tight tolerances (n is small; the weight is exact at any point, but
/// the proposal is best centred at the minimum).
NewtonOptions window_newton_options() {
  NewtonOptions opts;
  opts.max_iterations = 50;
  opts.gradient_tolerance = 1e-9;
  opts.step_tolerance = 1e-11;
  return opts;
}

}  // namespace

void SmootherOptions::validate(const Problem& p) const {
  require(members >= 2, "implicit smoother: expected at least 2 members (N), got {}", members);
  require(lag >= 1, "implicit smoother: expected a lag L >= 1 observation cycles, got {}", lag);
  require(std::isfinite(inflation) && inflation >= 1.0,
          "implicit smoother: expected a background inflation >= 1, got {}", inflation);
  require(starts >= 1 && starts <= members + 1,
          "implicit smoother: expected between 1 and N + 1 = {} Newton starts, got {}", members + 1,
          starts);
  require(bandwidth > 0.0 && bandwidth <= 1.0,
          "implicit smoother: expected a kernel bandwidth h in (0, 1], got {}", bandwidth);
  require(!p.stochastic(),
          "implicit smoother: the window's F assumes a perfect model, but the problem has model "
          "noise Q");
  require(p.steps_per_observation == 1,
          "implicit smoother: expected one model interval per observation (a perfect model over "
          "longer intervals is one longer interval), got {}",
          p.steps_per_observation);
}

void WindowTerms::set_log_norm() {
  const auto n = static_cast<int>(b_lower.rows()), m = static_cast<int>(r_lower.rows());
  log_norm = gaussian_log_normaliser(n + m, 0.0) + log_det_lower(b_lower) + log_det_lower(r_lower);
}

void prepare_scratch(const Problem& p, WindowObjective::Scratch& s) {
  const int n = p.dim(), m = p.obs_dim();
  p.model->prepare(s.forecast);
  s.state.resize(n);
  s.dx.resize(n);
  s.xi.resize(n);
  s.residual.resize(m);
}

double WindowObjective::evaluate(const Vector& x0, Vector* grad, Hessian* hess) const {
  const Problem& p = *p_;
  const WindowTerms& t = *t_;
  Scratch& s = *s_;
  const bool derivatives = grad != nullptr || hess != nullptr;
  s.state = x0;
  if (derivatives) s.jacobian.setIdentity(x0.size(), x0.size());
  for (int i = 0; i < t.lag; ++i) {
    if (!derivatives) {
      p.model->forecast(s.state, s.forecast);
      continue;
    }
    // dM^l/dx0 = J_l ... J_1, each J_i the derivative of one interval at its start.
    p.model->forecast_jacobian(s.state, s.step_jacobian, s.forecast);
    s.product.noalias() = s.step_jacobian * s.jacobian;
    s.jacobian.swap(s.product);
  }
  if (!s.state.allFinite()) return kInfinity;
  // Whitened residuals: L_R^-1 (y - H M^l(x0)) and L_B^-1 (x0 - b).
  s.residual = t.y;
  s.residual.noalias() -= p.H * s.state;
  t.r_lower.triangularView<Eigen::Lower>().solveInPlace(s.residual);
  s.dx = x0 - *b_;
  if (derivatives) {
    s.hr.noalias() = p.H * s.jacobian;  // L_R^-1 G, G = H dM^l/dx0
    t.r_lower.triangularView<Eigen::Lower>().solveInPlace(s.hr);
    if (grad != nullptr) {
      grad->noalias() = t.b_inv * s.dx;
      grad->noalias() -= s.hr.transpose() * s.residual;
    }
    if (hess != nullptr) {
      *hess = t.b_inv;
      hess->noalias() += s.hr.transpose() * s.hr;
    }
  }
  t.b_lower.triangularView<Eigen::Lower>().solveInPlace(s.dx);
  return 0.5 * (s.dx.squaredNorm() + s.residual.squaredNorm()) + t.log_norm;
}

ImplicitSmoother::ImplicitSmoother(Problem problem, SmootherOptions options)
    : problem_(std::move(problem)), options_(options) {
  problem_.validate();
  options_.validate(problem_);
  const auto count = static_cast<std::size_t>(options_.members);
  x0_.resize(count);
  end_.resize(count);
  weights_.assign(count, 1.0 / static_cast<double>(count));
  log_w_.assign(count, 0.0);
  scratch_.resize(count);
  for (auto& s : scratch_) prepare_scratch(problem_, s);
  terms_.r_lower = problem_.R.llt().matrixL();
  order_.resize(count);
  if (options_.bandwidth < 1.0) {
    kernel_terms_.r_lower = terms_.r_lower;
    centres_.resize(count);
  }
}

void ImplicitSmoother::initialize(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov) {
  initialize(initial_members(mean, cov, problem_.dim(), options_.members, options_.seed,
                             "implicit smoother"));
}

void ImplicitSmoother::initialize(const Eigen::MatrixXd& members) {
  require(members.rows() == problem_.dim() && members.cols() == options_.members,
          "implicit smoother: expected {} members of size {}, got {} of size {}", options_.members,
          problem_.dim(), members.cols(), members.rows());
  require(members.allFinite(), "implicit smoother: expected finite initial members");
  for (std::size_t j = 0; j < x0_.size(); ++j) {
    x0_[j] = members.col(static_cast<Eigen::Index>(j));
    end_[j] = x0_[j];
  }
  std::fill(weights_.begin(), weights_.end(), 1.0 / static_cast<double>(x0_.size()));
  cycle_ = 0;
  initialized_ = true;
}

Eigen::MatrixXd ImplicitSmoother::members() const {
  Eigen::MatrixXd e(problem_.dim(), static_cast<Eigen::Index>(x0_.size()));
  for (std::size_t j = 0; j < x0_.size(); ++j) e.col(static_cast<Eigen::Index>(j)) = x0_[j];
  return e;
}

Eigen::MatrixXd ImplicitSmoother::window_end_members() const {
  Eigen::MatrixXd e(problem_.dim(), static_cast<Eigen::Index>(end_.size()));
  for (std::size_t j = 0; j < end_.size(); ++j) e.col(static_cast<Eigen::Index>(j)) = end_[j];
  return e;
}

const Analysis& ImplicitSmoother::assimilate(const Eigen::VectorXd& y) {
  require(initialized_, "implicit smoother: initialize() must come before assimilate()");
  require_observation(problem_, y, cycle_ + 1);
  ++cycle_;
  analysis_ = Analysis{};
  if (cycle_ > options_.lag) {  // the window is full: its start moves one interval forward
    parallel_for(x0_.size(), [&](std::size_t j) {
      if (weights_[j] > 0.0) problem_.model->forecast(x0_[j], scratch_[j].forecast);
    });
  }
  terms_.lag = static_cast<int>(std::min<long>(cycle_, options_.lag));
  terms_.y = y;
  fit_background();
  if (options_.bandwidth < 1.0) {
    sample_kernels();
  } else {
    minimise();
    sample();
  }
  read_off();
  return analysis_;
}

void ImplicitSmoother::fit_background() {
  const int n = problem_.dim();
  // Serial sums in member order (the same bits for any thread count); members of weight 0
  // (a failed sample, possibly not finite) are left out.
  Eigen::VectorXd& b = terms_.b;
  b.setZero(n);
  double sum_sq = 0.0;
  for (std::size_t j = 0; j < x0_.size(); ++j) {
    if (weights_[j] <= 0.0) continue;
    b += weights_[j] * x0_[j];
    sum_sq += weights_[j] * weights_[j];
  }
  cov_.setZero(n, n);
  Eigen::VectorXd d(n);
  for (std::size_t j = 0; j < x0_.size(); ++j) {
    if (weights_[j] <= 0.0) continue;
    d = x0_[j] - b;
    cov_.selfadjointView<Eigen::Lower>().rankUpdate(d, weights_[j]);
  }
  cov_.triangularView<Eigen::StrictlyUpper>() = cov_.transpose();
  // 1 / (1 - sum w^2): the unbiased weighted covariance (N / (N - 1) for equal weights); a
  // single member of weight 1 leaves no spread to correct.
  const double correction = sum_sq < 1.0 ? 1.0 / (1.0 - sum_sq) : 1.0;
  cov_ *= correction * options_.inflation * options_.inflation;
  factor_background(cov_, terms_.b_lower);
  terms_.b_inv = terms_.b_lower.triangularView<Eigen::Lower>().solve(
      Eigen::MatrixXd::Identity(n, n));  // L_B^-1
  terms_.b_inv = terms_.b_inv.transpose() * terms_.b_inv;
  terms_.set_log_norm();
}

void ImplicitSmoother::minimise() {
  // Starts: b, then the heaviest members (ties by index), so that a second minimum of F that
  // the ensemble already sits in is found.
  std::iota(order_.begin(), order_.end(), std::size_t{0});
  std::stable_sort(order_.begin(), order_.end(),
                   [&](std::size_t a, std::size_t c) { return weights_[a] > weights_[c]; });
  const NewtonOptions opts = window_newton_options();
  const WindowObjective f(problem_, terms_, scratch_[0]);
  double best = kInfinity;
  bool found = false;
  for (int s = 0; s < options_.starts; ++s) {
    const Eigen::VectorXd& start = s == 0 ? terms_.b : x0_[order_[static_cast<std::size_t>(s - 1)]];
    if (s > 0 && !(weights_[order_[static_cast<std::size_t>(s - 1)]] > 0.0)) break;
    const auto r = newton_minimize<DenseFactor<Eigen::Dynamic>>(f, start, opts);
    if (!r.factor_ok || !(r.value < best)) continue;
    best = r.value;
    mu_ = r.x;
    h_lower_ = r.factor.matrixL();
    log_det_l_ = r.factor.log_det_L();
    found = true;
  }
  if (!found) {  // no finite minimum: sample the background itself (the weights stay exact)
    mu_ = terms_.b;
    h_lower_ = terms_.b_inv.llt().matrixL();
    log_det_l_ = log_det_lower(h_lower_);
  }
}

void ImplicitSmoother::sample() {
  const int n = problem_.dim();
  const auto c = static_cast<std::uint64_t>(cycle_);
  parallel_for(x0_.size(), [&](std::size_t j) {
    WindowObjective::Scratch& s = scratch_[j];
    Rng rng({options_.seed, c, j, purpose::kReference});
    rng.fill_normal(s.xi);
    // x0 = mu + L^-T xi: the linear map with the factor of the Hessian at the minimum.
    x0_[j] = s.xi;
    h_lower_.transpose().triangularView<Eigen::Upper>().solveInPlace(x0_[j]);
    x0_[j] += mu_;
    const WindowObjective f(problem_, terms_, s);
    const double fx = f.evaluate(x0_[j], nullptr, nullptr);
    end_[j] = s.state;
    log_w_[j] = implicit_log_weight(n, s.xi.squaredNorm(), fx, log_det_l_);
  });
}

void ImplicitSmoother::sample_kernels() {
  const int n = problem_.dim();
  const auto c = static_cast<std::uint64_t>(cycle_);
  const std::size_t count = x0_.size();
  // The members are resampled first: a kernel of small weight would spend its Newton run and its
  // draw where the posterior has almost no mass. Afterwards the mixture's weights are equal, and a
  // draw's weight is its kernel's implicit weight alone.
  Rng rng({options_.seed, c, 0, purpose::kResampling});
  uniforms_.resize(uniforms_needed(ResamplingScheme::kSystematic, count));
  for (double& u : uniforms_) u = rng.uniform();
  resample(ResamplingScheme::kSystematic, weights_, uniforms_, count, ancestors_);
  analysis_.resampled = true;
  // Kernel j: N(a x0_j + (1 - a) b, h^2 B), the shrinkage that keeps the mixture's mean b and
  // covariance B (Liu and West's kernel). The kernels share h^2 B, y and the lag; only the
  // centres differ.
  const double h = options_.bandwidth, a = std::sqrt(1.0 - h * h);
  for (std::size_t j = 0; j < count; ++j)
    centres_[j] = a * x0_[ancestors_[j]] + (1.0 - a) * terms_.b;
  WindowTerms& t = kernel_terms_;  // r_lower was set in the constructor
  t.b_lower = h * terms_.b_lower;
  t.b_inv = terms_.b_inv / (h * h);
  t.y = terms_.y;
  t.lag = terms_.lag;
  t.set_log_norm();
  const NewtonOptions opts = window_newton_options();
  parallel_for(count, [&](std::size_t j) {
    WindowObjective::Scratch& s = scratch_[j];
    const WindowObjective f(problem_, t, centres_[j], s);
    const auto r = newton_minimize<DenseFactor<Eigen::Dynamic>>(f, centres_[j], opts);
    Rng draws({options_.seed, c, j, purpose::kReference});
    draws.fill_normal(s.xi);
    double log_det = 0.0;
    if (r.factor_ok && std::isfinite(r.value)) {  // x0 = mu + L^-T xi, the linear map
      x0_[j] = s.xi;
      r.factor.matrixL().transpose().template triangularView<Eigen::Upper>().solveInPlace(x0_[j]);
      x0_[j] += r.x;
      log_det = r.factor.log_det_L();
    } else {  // no finite minimum: a draw of the kernel itself (the weight stays exact)
      x0_[j] = centres_[j];
      x0_[j].noalias() += t.b_lower * s.xi;
      log_det = -log_det_lower(t.b_lower);
    }
    const double fx = f.evaluate(x0_[j], nullptr, nullptr);
    end_[j] = s.state;
    log_w_[j] = implicit_log_weight(n, s.xi.squaredNorm(), fx, log_det);
  });
}

void ImplicitSmoother::read_off() {
  const int n = problem_.dim();
  const double top = *std::max_element(log_w_.begin(), log_w_.end());
  int failures = 0;
  double total = 0.0;
  for (std::size_t j = 0; j < log_w_.size(); ++j) {
    const bool failed = !(log_w_[j] > -kInfinity);
    failures += failed ? 1 : 0;
    weights_[j] = failed || !(top > -kInfinity) ? 0.0 : std::exp(log_w_[j] - top);
    total += weights_[j];
  }
  if (!(total > 0.0)) {  // every sample failed: keep equal weights (an uninformed analysis)
    std::fill(weights_.begin(), weights_.end(), 1.0 / static_cast<double>(weights_.size()));
    total = 1.0;
  }
  double sum_sq = 0.0;
  for (double& w : weights_) {
    w /= total;
    sum_sq += w * w;
  }
  analysis_.mean.setZero(n);
  for (std::size_t j = 0; j < end_.size(); ++j)
    if (weights_[j] > 0.0) analysis_.mean += weights_[j] * end_[j];
  double var = 0.0;
  for (std::size_t j = 0; j < end_.size(); ++j)
    if (weights_[j] > 0.0) var += weights_[j] * (end_[j] - analysis_.mean).squaredNorm();
  analysis_.spread = std::sqrt(var / n);
  analysis_.ess = 1.0 / sum_sq;
  analysis_.sampling_failures = failures;
}

}  // namespace implicit::da
