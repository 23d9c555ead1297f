#include "implicit/da/filters.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/da/path_objective.hpp"

namespace implicit::da {
namespace {

// Stream purposes: the regularisation and the EnKF's observation perturbations are the
// proposal draws of their filters (neither filter draws other proposal numbers).
constexpr std::uint64_t kJitter = purpose::kProposal;
constexpr std::uint64_t kPerturbation = purpose::kProposal;

/// The parts of the implicit filter's F that all members share in one cycle, with
/// |y - H x|^2_{R^-1} = x^T G x - 2 b^T x + y^T R^-1 y, so that evaluating F needs no
/// observation-sized temporaries: F(x) = 1/2 dx^T Q^-1 dx + 1/2 x^T G x - b^T x + c, dx = x - m.
template <int N>
struct ImplicitTerms {
  Mat<N> q_inv, g;
  Vec<N> b;
  double c = 0.0;
};

template <int N>
struct ImplicitObjective {
  using Vector = Vec<N>;
  using Hessian = Mat<N>;
  const ImplicitTerms<N>* t;
  Vector m;  ///< M(x') of this member

  double evaluate(const Vector& x, Vector* grad, Hessian* hess) const {
    const Vector dx = x - m;
    const Vector q_dx = t->q_inv * dx;
    const Vector gx = t->g * x;
    if (grad) *grad = q_dx + gx - t->b;
    if (hess) *hess = t->q_inv + t->g;
    return 0.5 * dx.dot(q_dx) + 0.5 * x.dot(gx) - t->b.dot(x) + t->c;
  }
};

template <int N>
ImplicitTerms<N> implicit_terms(const Eigen::MatrixXd& q_inv, const Eigen::MatrixXd& g,
                                const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                                const Eigen::VectorXd& y, double log_norm) {
  ImplicitTerms<N> t;
  t.q_inv = q_inv;
  t.g = g;
  const Eigen::VectorXd r_inv_y = R.llt().solve(y);
  t.b = H.transpose() * r_inv_y;
  t.c = 0.5 * y.dot(r_inv_y) + log_norm;
  return t;
}

/// Draws `out` around Newton's minimum r of f by the linear or random map; returns its log
/// weight (-inf and `failed` when Newton found no SPD factor or the random map's ray had no root).
template <typename Factor, typename F>
double implicit_draw(const F& f, const NewtonMinimum<Factor>& r, Rng& rng, ImplicitMap map,
                     typename Factor::Vector& out, bool& failed) {
  if (!r.factor_ok) {
    failed = true;
    return -kInfinity;
  }
  typename Factor::Vector xi(r.x.size());
  rng.fill_normal(xi);
  if (map == ImplicitMap::kLinear) return linear_map(f, r.x, r.factor, xi, out);
  double log_w = -kInfinity;
  if (random_map(f, r.x, r.value, r.factor, xi, out, log_w) != RayStatus::kOk) {
    failed = true;
    return -kInfinity;
  }
  return log_w;
}

/// Moves x = M(x') to an implicit sample of F; returns its log weight.
template <int N>
double implicit_move(const ImplicitTerms<N>& t, Eigen::VectorXd& x, Rng& rng, ImplicitMap map,
                     bool& failed) {
  const ImplicitObjective<N> f{&t, x};
  const auto r = newton_minimize<DenseFactor<N>>(f, f.m);
  Vec<N> out(x.size());
  const double log_w = implicit_draw(f, r, rng, map, out, failed);
  if (!failed) x = out;
  return log_w;
}

/// The same over the K interval noises of a path (path_objective.hpp): x (the parent on entry)
/// becomes the end of the sampled path.
double implicit_path_move(const Problem& p, const PathTerms& t, PathObjective::Scratch& s,
                          Eigen::VectorXd& parent, Eigen::VectorXd& x, Rng& rng, ImplicitMap map,
                          bool& failed) {
  parent = x;
  const PathObjective f(p, t, parent, s);
  const Eigen::Index size = static_cast<Eigen::Index>(p.dim()) * t.steps;
  const auto r = newton_minimize<DenseFactor<Eigen::Dynamic>>(f, Eigen::VectorXd::Zero(size),
                                                              path_newton_options());
  Eigen::VectorXd w(size);
  const double log_w = implicit_draw(f, r, rng, map, w, failed);
  if (!failed) f.end_state(w, x);
  return log_w;
}

double log_det(const Eigen::MatrixXd& lower_factor) {
  return 2.0 * lower_factor.diagonal().array().log().sum();
}

}  // namespace

std::string_view to_string(Method m) {
  switch (m) {
    case Method::kBootstrap:
      return "bootstrap";
    case Method::kImplicit:
      return "implicit";
    case Method::kEnkf:
      return "enkf";
    case Method::kEtkf:
      return "etkf";
  }
  return "unknown";
}

Method parse_method(std::string_view name) {
  for (auto m : {Method::kBootstrap, Method::kImplicit, Method::kEnkf, Method::kEtkf})
    if (name == to_string(m)) return m;
  throw InvalidArgument(fmt::format(
      "data assimilation method: expected bootstrap, implicit, enkf or etkf, got '{}'", name));
}

std::string_view to_string(Regularisation r) {
  return r == Regularisation::kIsotropic ? "iso" : "cov";
}

Regularisation parse_regularisation(std::string_view name) {
  for (auto r : {Regularisation::kIsotropic, Regularisation::kCovariance})
    if (name == to_string(r)) return r;
  throw InvalidArgument(
      fmt::format("particle filter regularisation: expected iso or cov, got '{}'", name));
}

double silverman_bandwidth(int members, int dim) {
  require(members >= 1 && dim >= 1,
          "Silverman bandwidth: expected N >= 1 and n >= 1, got N = {}, n = {}", members, dim);
  const double n = dim;
  return std::pow(4.0 / (members * (n + 2.0)), 1.0 / (n + 4.0));
}

void weighted_covariance(std::span<const Eigen::VectorXd> members, std::span<const double> weights,
                         Eigen::MatrixXd& cov) {
  require(!members.empty() && members.size() == weights.size(),
          "weighted covariance: expected one weight per member, got {} members, {} weights",
          members.size(), weights.size());
  const Eigen::Index n = members[0].size();
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(n);
  for (std::size_t j = 0; j < members.size(); ++j) mean += weights[j] * members[j];
  cov.setZero(n, n);
  Eigen::VectorXd d(n);
  for (std::size_t j = 0; j < members.size(); ++j) {
    d = members[j] - mean;
    cov.selfadjointView<Eigen::Lower>().rankUpdate(d, weights[j]);
  }
  cov.triangularView<Eigen::StrictlyUpper>() = cov.transpose();
}

Eigen::MatrixXd initial_members(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov, int dim,
                                int count, std::uint64_t seed, const char* who) {
  require(mean.size() == dim && mean.allFinite(),
          "{}: expected a finite initial mean of size {}, got size {}", who, dim, mean.size());
  require_spd(cov, dim, "initial covariance");
  const Eigen::MatrixXd l = cov.llt().matrixL();
  Eigen::MatrixXd members(dim, count);
  Eigen::VectorXd z(dim);
  for (int j = 0; j < count; ++j) {
    Rng rng({seed, 0, static_cast<std::uint64_t>(j), purpose::kInitial});
    rng.fill_normal(z);
    members.col(j) = mean + l * z;
  }
  return members;
}

double covariance_factor(const Eigen::MatrixXd& cov, Eigen::MatrixXd& lower) {
  require(cov.allFinite(), "covariance regularisation: the ensemble covariance is not finite");
  const Eigen::Index n = cov.rows();
  Eigen::LLT<Eigen::MatrixXd> llt(cov);
  double ridge = 0.0;
  if (llt.info() != Eigen::Success) {
    const double scale = cov.trace() / static_cast<double>(n);
    ridge = scale > 0.0 ? 1e-10 * scale : 1e-12;
    for (;; ridge *= 10.0) {
      llt.compute(cov + ridge * Eigen::MatrixXd::Identity(n, n));
      if (llt.info() == Eigen::Success) break;
    }
  }
  lower = llt.matrixL();
  return ridge;
}

void FilterOptions::validate(const Problem& p) const {
  require(members >= 2, "ensemble filter: expected at least 2 members (N), got {}", members);
  require(std::isfinite(jitter) && jitter >= 0.0,
          "ensemble filter: expected a jitter std >= 0, got {}", jitter);
  require(std::isfinite(inflation) && inflation >= 1.0,
          "ensemble filter: expected a multiplicative inflation >= 1, got {}", inflation);
  require(resample_threshold >= 0.0 && resample_threshold <= 1.0,
          "ensemble filter: expected a resampling threshold N_eff/N in [0, 1], got {}",
          resample_threshold);
  require(method != Method::kImplicit || p.stochastic() || jitter > 0.0,
          "implicit particle filter: the model is deterministic, so the jitter plays the role of "
          "the model noise Q = jitter^2 I (iso) or (jitter h)^2 C (cov): expected a jitter > 0, "
          "got {}",
          jitter);
  require(method != Method::kImplicit || p.steps_per_observation == 1 || p.stochastic() ||
              regularisation == Regularisation::kIsotropic,
          "implicit particle filter: with {} model intervals per observation the noise of each "
          "interval is sampled, so Q must be the problem's or jitter^2 I (iso); covariance "
          "regularisation is refused",
          p.steps_per_observation);
}

EnsembleFilter::EnsembleFilter(Problem problem, FilterOptions options)
    : problem_(std::move(problem)), options_(options) {
  problem_.validate();
  options_.validate(problem_);
  const int n = problem_.dim(), p = problem_.obs_dim();
  slots_.resize(static_cast<std::size_t>(options_.members));
  for (auto& s : slots_) {
    problem_.model->prepare(s.forecast);
    s.noise.resize(n);
    s.residual.resize(p);
    if (path_sampling()) prepare_scratch(problem_, s.path);
  }
  lr_ = problem_.R.llt().matrixL();
  log_det_2pi_r_ = 2.0 * gaussian_log_normaliser(p, 0.5 * log_det(lr_));
  if (problem_.stochastic()) lq_ = problem_.Q.llt().matrixL();
  if (options_.method == Method::kImplicit) {
    g_ = problem_.H.transpose() * problem_.R.llt().solve(problem_.H);
    // With covariance regularisation on a deterministic model, Q is set every cycle instead.
    set_implicit_q(problem_.stochastic() ? problem_.Q
                                         : Eigen::MatrixXd(options_.jitter * options_.jitter *
                                                           Eigen::MatrixXd::Identity(n, n)));
  }
  ancestors_.reserve(slots_.size());
}

void EnsembleFilter::initialize(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov) {
  initialize(initial_members(mean, cov, problem_.dim(), options_.members, options_.seed,
                             "ensemble filter"));
}

void EnsembleFilter::initialize(const Eigen::MatrixXd& members) {
  require(members.rows() == problem_.dim() && members.cols() == options_.members,
          "ensemble filter: expected {} members of size {}, got {} of size {}", options_.members,
          problem_.dim(), members.cols(), members.rows());
  require(members.allFinite(), "ensemble filter: expected finite initial members");
  std::vector<Eigen::VectorXd> ps(static_cast<std::size_t>(members.cols()));
  for (Eigen::Index j = 0; j < members.cols(); ++j)
    ps[static_cast<std::size_t>(j)] = members.col(j);
  engine_.assign(std::span<const Eigen::VectorXd>(ps));
  ensemble_.resize(members.rows(), members.cols());
  cycle_ = 0;
  initialized_ = true;
}

void EnsembleFilter::set_implicit_q(const Eigen::MatrixXd& q) {
  const int n = problem_.dim();
  const Eigen::LLT<Eigen::MatrixXd> q_llt(q);
  q_inv_ = q_llt.solve(Eigen::MatrixXd::Identity(n, n));
  log_norm_ = gaussian_log_normaliser(n, 0.5 * log_det(q_llt.matrixL())) + 0.5 * log_det_2pi_r_;
}

void EnsembleFilter::factor_ensemble_covariance() {
  weighted_covariance(engine_.particles(), engine_.weights(), cov_);
  covariance_factor(cov_, cov_l_);
}

Eigen::MatrixXd EnsembleFilter::members() const {
  const auto ps = engine_.particles();
  Eigen::MatrixXd e(problem_.dim(), static_cast<Eigen::Index>(ps.size()));
  for (std::size_t j = 0; j < ps.size(); ++j) e.col(static_cast<Eigen::Index>(j)) = ps[j];
  return e;
}

const Analysis& EnsembleFilter::assimilate(const Eigen::VectorXd& y) {
  require(initialized_, "ensemble filter: initialize() must come before assimilate()");
  require_observation(problem_, y, cycle_ + 1);
  ++cycle_;
  analysis_.resampled = false;
  analysis_.sampling_failures = 0;
  forecast_and_weigh(y);
  if (options_.method == Method::kEnkf || options_.method == Method::kEtkf) ensemble_analysis(y);
  read_off_and_resample();
  return analysis_;
}

void EnsembleFilter::forecast_and_weigh(const Eigen::VectorXd& y) {
  const auto c = static_cast<std::uint64_t>(cycle_);
  const auto seed = options_.seed;
  const Method method = options_.method;
  const bool noisy = problem_.stochastic() && method != Method::kImplicit;
  const int steps = problem_.steps_per_observation;
  std::vector<char> failed(slots_.size(), 0);
  // Fixed sizes for Lorenz-63 (3) and the Lorenz-96 benchmark (10): Newton and the maps then
  // run without heap allocation per member; other sizes take the dynamic path.
  ImplicitTerms<3> t3;
  ImplicitTerms<10> t10;
  ImplicitTerms<Eigen::Dynamic> tx;
  const int n = problem_.dim();
  const auto forecast = [&](std::size_t j, Eigen::VectorXd& x) {
    Slot& s = slots_[j];
    Rng rng({seed, c, j, purpose::kProcessNoise});  // one stream for the K intervals' noises
    for (int i = 0; i < steps; ++i) {
      problem_.model->forecast(x, s.forecast);
      if (noisy) {  // x += L_Q z: the model noise (the implicit filter samples it in F instead)
        rng.fill_normal(s.noise);
        x.noalias() += lq_ * s.noise;
      }
    }
  };
  // Implicit filter, deterministic model, covariance regularisation: Q = (jitter h)^2 C needs
  // the whole forecast ensemble, so the forecast is a move of its own (increments 0) first.
  const bool ensemble_q = method == Method::kImplicit && !problem_.stochastic() &&
                          options_.regularisation == Regularisation::kCovariance;
  if (ensemble_q) {
    engine_.move([&](std::size_t j, Eigen::VectorXd& x) {
      forecast(j, x);
      return 0.0;
    });
    factor_ensemble_covariance();
    const double s = options_.jitter * silverman_bandwidth(options_.members, n);
    set_implicit_q(s * s * (cov_l_ * cov_l_.transpose()));
  }
  if (path_sampling()) {  // K > 1 intervals: implicit sampling of the K noises of each path
    const PathTerms t(problem_,
                      problem_.stochastic() ? problem_.Q
                                            : Eigen::MatrixXd(options_.jitter * options_.jitter *
                                                              Eigen::MatrixXd::Identity(n, n)),
                      y);
    engine_.move([&](std::size_t j, Eigen::VectorXd& x) {
      Slot& s = slots_[j];
      Rng rng({seed, c, j, purpose::kReference});
      bool bad = false;
      const double lw =
          implicit_path_move(problem_, t, s.path, s.parent, x, rng, options_.map, bad);
      failed[j] = bad ? 1 : 0;
      return lw;
    });
    for (char f : failed) analysis_.sampling_failures += f;
    return;
  }
  if (method == Method::kImplicit) {
    const auto& H = problem_.H;
    const auto& R = problem_.R;
    if (n == 3)
      t3 = implicit_terms<3>(q_inv_, g_, H, R, y, log_norm_);
    else if (n == 10)
      t10 = implicit_terms<10>(q_inv_, g_, H, R, y, log_norm_);
    else
      tx = implicit_terms<Eigen::Dynamic>(q_inv_, g_, H, R, y, log_norm_);
  }
  engine_.move([&](std::size_t j, Eigen::VectorXd& x) {
    Slot& s = slots_[j];
    if (!ensemble_q) forecast(j, x);
    if (method == Method::kImplicit) {
      Rng rng({seed, c, j, purpose::kReference});
      bool bad = false;
      const double lw = n == 3    ? implicit_move(t3, x, rng, options_.map, bad)
                        : n == 10 ? implicit_move(t10, x, rng, options_.map, bad)
                                  : implicit_move(tx, x, rng, options_.map, bad);
      failed[j] = bad ? 1 : 0;
      return lw;
    }
    if (method != Method::kBootstrap) return 0.0;
    s.residual = y;  // log N(y; H x, R)
    s.residual.noalias() -= problem_.H * x;
    lr_.triangularView<Eigen::Lower>().solveInPlace(s.residual);
    return -0.5 * (s.residual.squaredNorm() + log_det_2pi_r_);
  });
  for (char f : failed) analysis_.sampling_failures += f;
}

void EnsembleFilter::ensemble_analysis(const Eigen::VectorXd& y) {
  auto ps = engine_.particles();
  const auto m = static_cast<Eigen::Index>(ps.size());
  for (Eigen::Index j = 0; j < m; ++j) ensemble_.col(j) = ps[static_cast<std::size_t>(j)];
  if (options_.inflation != 1.0) {
    const Eigen::VectorXd mean = ensemble_.rowwise().mean();
    ensemble_ = ((ensemble_.colwise() - mean) * options_.inflation).colwise() + mean;
  }
  if (options_.method == Method::kEtkf) {
    etkf_analysis(ensemble_, problem_.H, problem_.R, y);
  } else {
    Eigen::MatrixXd normals(problem_.obs_dim(), m);
    for (Eigen::Index j = 0; j < m; ++j) {
      Rng rng({options_.seed, static_cast<std::uint64_t>(cycle_), static_cast<std::uint64_t>(j),
               kPerturbation});
      auto col = normals.col(j);
      rng.fill_normal(col);
    }
    enkf_perturbed_analysis(ensemble_, problem_.H, problem_.R, lr_, y, normals);
  }
  for (Eigen::Index j = 0; j < m; ++j) ps[static_cast<std::size_t>(j)] = ensemble_.col(j);
}

void EnsembleFilter::read_off_and_resample() {
  const Method method = options_.method;
  const bool particle = method == Method::kBootstrap || method == Method::kImplicit;
  const auto r = engine_.reweight();  // the EnKFs' increments are 0: weights stay equal
  const auto ps = engine_.particles();
  const auto w = engine_.weights();
  const int n = problem_.dim();
  // Serial reductions in member order: the same sums for any thread count.
  analysis_.mean.setZero(n);
  for (std::size_t j = 0; j < ps.size(); ++j) analysis_.mean += w[j] * ps[j];
  double var = 0.0;
  for (std::size_t j = 0; j < ps.size(); ++j) var += w[j] * (ps[j] - analysis_.mean).squaredNorm();
  const double m = static_cast<double>(ps.size());
  if (!particle) var *= m / (m - 1.0);  // the EnKFs' unbiased ensemble covariance
  analysis_.spread = std::sqrt(var / n);
  analysis_.ess = particle ? r.ess : m;
  if (!particle || !needs_resampling(r.ess, ps.size(), options_.resample_threshold)) return;
  const bool cov_jitter = method == Method::kBootstrap && options_.jitter > 0.0 &&
                          options_.regularisation == Regularisation::kCovariance;
  if (cov_jitter) factor_ensemble_covariance();  // of the weighted ensemble, before resampling
  Rng rng({options_.seed, static_cast<std::uint64_t>(cycle_), 0, purpose::kResampling});
  uniforms_.resize(uniforms_needed(ResamplingScheme::kSystematic, ps.size()));
  for (double& u : uniforms_) u = rng.uniform();
  resample(ResamplingScheme::kSystematic, w, uniforms_, ps.size(), ancestors_);
  engine_.resample(ancestors_);
  analysis_.resampled = true;
  if (method != Method::kBootstrap || options_.jitter == 0.0) return;
  const auto c = static_cast<std::uint64_t>(cycle_);
  if (cov_jitter) {  // x += jitter h L N(0, I), L L^T = C
    // Scaled once here: (scale * L) * z inside the move would build an n x n temporary per member.
    cov_l_ *= options_.jitter * silverman_bandwidth(options_.members, n);
    engine_.move([&](std::size_t j, Eigen::VectorXd& x) {
      Rng jitter_rng({options_.seed, c, j, kJitter});
      Eigen::VectorXd& z = slots_[j].noise;
      jitter_rng.fill_normal(z);
      x.noalias() += cov_l_ * z;
      return 0.0;
    });
    return;
  }
  engine_.move([&](std::size_t j, Eigen::VectorXd& x) {  // regularisation: x += jitter N(0, I)
    Rng jitter_rng({options_.seed, c, j, kJitter});
    for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += options_.jitter * jitter_rng.normal();
    return 0.0;
  });
}

}  // namespace implicit::da
