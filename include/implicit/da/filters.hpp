#pragma once
// Ensemble filters of data assimilation on one Problem (model.hpp): the bootstrap particle
// filter and the implicit particle filter on the sequential Monte Carlo engine
// (filter/particle_engine.hpp), and the stochastic (perturbed-observation) EnKF and the
// square-root ETKF as baselines (docs/specification.md, "Data assimilation").
//
//   implicit::da::FilterOptions o{.method = Method::kImplicit, .members = 100, .jitter = 0.3};
//   implicit::da::EnsembleFilter f(problem, o);
//   f.initialize(x0, 2.0 * Eigen::MatrixXd::Identity(3, 3));
//   for (const auto& y : observations) {
//     const auto& a = f.assimilate(y);   // forecast one interval, then analyse y
//     use(a.mean, a.spread, a.ess);
//   }
//
// Every cycle's draws come from streams keyed by (seed, cycle, member, purpose), and every
// member is moved in parallel in its own slot (with its own forecast workspace), so results are
// bit-identical for any number of threads.
//
// Bootstrap: members move with the model (plus Q noise), weights multiply by p(y | x); when
// N_eff < resample_threshold N the population is resampled (systematic) and every member is
// regularised: `jitter` * N(0, I) is added (Regularisation::kIsotropic), or, with
// Regularisation::kCovariance, `jitter` * h * L * N(0, I), where L L^T = C is the weighted
// covariance of the ensemble before resampling and h = (4 / (N (n + 2)))^(1 / (n + 4)) is
// Silverman's bandwidth: `jitter` is then a factor on a kernel width that shrinks with N.
// Implicit: each member x' is moved by implicit sampling of
//   F(x) = 1/2 |x - M(x')|^2_{Q^-1} + 1/2 |y - H x|^2_{R^-1} + 1/2 log det 2 pi Q
//          + 1/2 log det 2 pi R,
// minimised by core's Newton and sampled by the linear (or random) map with core's exact weight,
// whose expectation over the reference variable is p(y | x'). With K = steps_per_observation > 1
// intervals per observation, each with its noise Q, the variables are the K noises of the
// member's path instead (path_objective.hpp), and the other filters forecast K noisy intervals.
// A deterministic model has no Q: the
// jitter plays its role, Q = jitter^2 I (isotropic), or Q = (jitter h)^2 C with C the weighted
// covariance of the forecast ensemble of the cycle (covariance regularisation), and no jitter is
// added after resampling.
// EnKF / ETKF: forecast anomalies are multiplied by `inflation`, then the perturbed-observation
// (observation perturbations not re-centred) or the symmetric square-root analysis.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/types.hpp"
#include "implicit/da/model.hpp"
#include "implicit/da/path_objective.hpp"
#include "implicit/filter/particle_engine.hpp"

namespace implicit::da {

enum class Method { kBootstrap, kImplicit, kEnkf, kEtkf };
/// The implicit filter's map (core/types.hpp).
using ImplicitMap = MapKind;
enum class Regularisation { kIsotropic, kCovariance };

std::string_view to_string(Method m);
/// "bootstrap", "implicit", "enkf" or "etkf"; throws InvalidArgument otherwise.
Method parse_method(std::string_view name);
std::string_view to_string(Regularisation r);
/// "iso" or "cov"; throws InvalidArgument otherwise.
Regularisation parse_regularisation(std::string_view name);

struct FilterOptions {
  Method method = Method::kEtkf;
  int members = 10;     ///< N, at least 2
  double jitter = 0.0;  ///< std (isotropic) or factor (covariance) of the regularisation
  Regularisation regularisation = Regularisation::kIsotropic;
  double inflation = 1.0;           ///< multiplicative on the forecast anomalies (EnKF, ETKF)
  double resample_threshold = 0.5;  ///< resample when N_eff < threshold * N (particle filters)
  ImplicitMap map = ImplicitMap::kLinear;
  std::uint64_t seed = 1;

  /// Throws InvalidArgument naming the option (N < 2, negative jitter, inflation < 1, a
  /// threshold outside [0, 1], the implicit filter on a deterministic model without jitter).
  void validate(const Problem& p) const;
};

/// What one cycle's analysis gives.
struct Analysis {
  Eigen::VectorXd mean;       ///< (weighted) ensemble mean
  double spread = 0.0;        ///< sqrt of the mean (over components) ensemble variance
  double ess = 0.0;           ///< N_eff of the analysis weights (N for the EnKFs)
  bool resampled = false;     ///< the particle filter resampled after this analysis
  int sampling_failures = 0;  ///< implicit: members whose Newton or map failed (weight 0)
};

class EnsembleFilter {
 public:
  /// Validates the problem and the options (throws InvalidArgument).
  EnsembleFilter(Problem problem, FilterOptions options);

  /// Members drawn from N(mean, cov), equal weights (streams (seed, 0, j, kInitial)).
  void initialize(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov);
  /// The given members (one per column), equal weights.
  void initialize(const Eigen::MatrixXd& members);

  /// Forecasts every member one interval, then analyses `y` (throws InvalidArgument for a wrong
  /// size or a NaN). Cycles are numbered from 1; the number keys the cycle's random streams.
  const Analysis& assimilate(const Eigen::VectorXd& y);

  long cycle() const { return cycle_; }
  /// The members (columns) and their normalised weights after the last cycle.
  Eigen::MatrixXd members() const;
  std::span<const double> weights() const { return engine_.weights(); }
  const Problem& problem() const { return problem_; }
  const FilterOptions& options() const { return options_; }

 private:
  struct Slot {  // per-member scratch, reused every cycle
    ForecastWorkspace forecast;
    Eigen::VectorXd noise, residual, parent;
    PathObjective::Scratch path;  ///< implicit filter over K > 1 intervals
  };
  bool path_sampling() const {
    return options_.method == Method::kImplicit && problem_.steps_per_observation > 1;
  }
  void forecast_and_weigh(const Eigen::VectorXd& y);
  void ensemble_analysis(const Eigen::VectorXd& y);
  void read_off_and_resample();
  void factor_ensemble_covariance();  ///< cov_, cov_l_ from the current members and weights
  void set_implicit_q(const Eigen::MatrixXd& q);  ///< q_inv_, log_norm_

  Problem problem_;
  FilterOptions options_;
  filter::ParticleEngine<Eigen::VectorXd> engine_;
  std::vector<Slot> slots_;
  std::vector<std::size_t> ancestors_;
  std::vector<double> uniforms_;
  Eigen::MatrixXd lq_, lr_;      ///< Cholesky factors of Q (empty: none) and R
  Eigen::MatrixXd q_inv_, g_;    ///< implicit: Q^-1 (Q = jitter^2 I if deterministic), H^T R^-1 H
  double log_norm_ = 0.0;        ///< 1/2 log det 2 pi Q + 1/2 log det 2 pi R (implicit F)
  double log_det_2pi_r_ = 0.0;   ///< log det 2 pi R (bootstrap likelihood)
  Eigen::MatrixXd ensemble_;     ///< EnKF / ETKF work matrix, n x N
  Eigen::MatrixXd cov_, cov_l_;  ///< covariance regularisation: C and its Cholesky factor
  Analysis analysis_;
  long cycle_ = 0;
  bool initialized_ = false;
};

/// Silverman's rule-of-thumb bandwidth h = (4 / (N (n + 2)))^(1 / (n + 4)) of a Gaussian kernel
/// density estimate from N samples in dimension n (N, n >= 1).
double silverman_bandwidth(int members, int dim);

/// C = sum_j w_j (x_j - xbar)(x_j - xbar)^T with xbar = sum_j w_j x_j (weights normalised),
/// summed serially in member order (the same bits for any thread count).
void weighted_covariance(std::span<const Eigen::VectorXd> members, std::span<const double> weights,
                         Eigen::MatrixXd& cov);

/// N members drawn from N(mean, cov), member j from the stream (seed, 0, j, kInitial), so each
/// member's draw is the same for any N and thread count. `who` names the caller in the errors (a
/// mean of the wrong size or not finite, a covariance not SPD).
Eigen::MatrixXd initial_members(const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov, int dim,
                                int count, std::uint64_t seed, const char* who);

/// The lower Cholesky factor of `cov` into `lower`. A covariance that is not numerically positive
/// definite (members collapsed onto one point or a subspace) gets a ridge eps I added first, eps
/// = 1e-10 times its mean variance (1e-12 if that is 0), multiplied by 10 until the factor exists:
/// the regularisation then stays (almost) within the ensemble's span. Returns the ridge (0: none).
double covariance_factor(const Eigen::MatrixXd& cov, Eigen::MatrixXd& lower);

/// The perturbed-observation EnKF analysis of the members E (columns, already inflated):
/// K = A S^T (S S^T + (N-1) R)^-1 with A the anomalies and S = H A, and each member moved by
/// K (y + L_R e_j - H x_j), with e_j the j-th column of `normals` (p x N standard normals) and
/// L_R the Cholesky factor of R.
void enkf_perturbed_analysis(Eigen::MatrixXd& E, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                             const Eigen::MatrixXd& lr, const Eigen::VectorXd& y,
                             const Eigen::MatrixXd& normals);

/// The ETKF (symmetric square root) analysis of the members E (columns, already inflated).
void etkf_analysis(Eigen::MatrixXd& E, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                   const Eigen::VectorXd& y);

}  // namespace implicit::da
