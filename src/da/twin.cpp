#include "implicit/da/twin.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"

namespace implicit::da {

double analysis_rmse(std::span<const Eigen::VectorXd> means, std::span<const Eigen::VectorXd> truth,
                     std::size_t first) {
  require(means.size() == truth.size() && first < means.size(),
          "analysis rmse: expected as many means as truths and a cycle to score, got {} means, "
          "{} truths, first scored {}",
          means.size(), truth.size(), first);
  double sum = 0.0;
  for (std::size_t k = first; k < means.size(); ++k)
    sum += std::sqrt((means[k] - truth[k]).squaredNorm() / static_cast<double>(truth[k].size()));
  return sum / static_cast<double>(means.size() - first);
}

namespace {

void check_settings(const TwinSettings& s) {
  require(s.cycles >= 1, "twin experiment: expected at least 1 cycle, got {}", s.cycles);
  require(std::isfinite(s.interval) && s.interval > 0.0,
          "twin experiment: expected a positive time between observations, got {}", s.interval);
  require(std::isfinite(s.burn_in) && s.burn_in >= 0.0,
          "twin experiment: expected a burn-in >= 0, got {}", s.burn_in);
  require(s.cycles * s.interval > s.burn_in,
          "twin experiment: the burn-in {} covers all {} cycles ({} time units): nothing to score",
          s.burn_in, s.cycles, s.cycles * s.interval);
}

/// The truth, the observations and the scores around any assimilator with
/// `const Analysis& assimilate(const Eigen::VectorXd&)` (an EnsembleFilter or ImplicitSmoother).
template <typename Assimilator>
TwinResult run_twin_with(const Problem& p, Assimilator& filter, const TwinSettings& s) {
  require(s.truth0.size() == p.dim() && s.truth0.allFinite(),
          "twin experiment: expected a finite initial truth of size {}, got size {}", p.dim(),
          s.truth0.size());
  filter.initialize(s.mean0, s.cov0);

  const int n = p.dim(), m = p.obs_dim();
  const Eigen::MatrixXd lr = p.R.llt().matrixL();
  Eigen::MatrixXd lq;
  if (p.stochastic()) lq = p.Q.llt().matrixL();
  ForecastWorkspace w;
  p.model->prepare(w);
  Eigen::VectorXd truth = s.truth0, y(m), z_obs(m), z_model(n);
  TwinResult r;
  double rmse_sum = 0.0, spread_sum = 0.0, ess_sum = 0.0, seconds = 0.0;
  for (int k = 1; k <= s.cycles; ++k) {
    const auto step = static_cast<std::uint64_t>(k);
    for (int i = 0; i < p.steps_per_observation; ++i) {
      p.model->forecast(truth, w);
      if (p.stochastic()) {  // interval i's noise: stream (seed, k, 1 + i, kData)
        Rng rng({s.seed, step, 1 + static_cast<std::uint64_t>(i), purpose::kData});
        rng.fill_normal(z_model);
        truth += lq * z_model;
      }
    }
    Rng obs_rng({s.seed, step, 0, purpose::kData});
    obs_rng.fill_normal(z_obs);
    require(truth.allFinite(),
            "twin experiment: the truth is not finite at cycle {} (the model is unstable with "
            "these settings)",
            k);
    y = p.H * truth + lr * z_obs;
    const auto start = std::chrono::steady_clock::now();
    const Analysis& a = filter.assimilate(y);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!a.mean.allFinite()) {
      r.diverged_at = k;
      break;
    }
    r.resamplings += a.resampled ? 1 : 0;
    r.sampling_failures += a.sampling_failures;
    if (s.keep_history) {
      r.truth.push_back(truth);
      r.means.push_back(a.mean);
    }
    if (!(k * s.interval > s.burn_in)) continue;
    ++r.scored_cycles;
    rmse_sum += std::sqrt((a.mean - truth).squaredNorm() / n);
    spread_sum += a.spread;
    ess_sum += a.ess;
  }
  if (r.diverged_at > 0) {
    r.rmse_a = r.spread_a = r.mean_ess = std::numeric_limits<double>::quiet_NaN();
    r.ms_per_cycle = 1e3 * seconds / r.diverged_at;
    return r;
  }
  r.rmse_a = rmse_sum / r.scored_cycles;
  r.spread_a = spread_sum / r.scored_cycles;
  r.mean_ess = ess_sum / r.scored_cycles;
  r.ms_per_cycle = 1e3 * seconds / s.cycles;
  return r;
}

}  // namespace

TwinResult run_twin(const Problem& p, const FilterOptions& o, const TwinSettings& s) {
  check_settings(s);
  EnsembleFilter filter(p, o);  // validates p and o
  return run_twin_with(p, filter, s);
}

TwinResult run_twin(const Problem& p, const SmootherOptions& o, const TwinSettings& s) {
  check_settings(s);
  ImplicitSmoother smoother(p, o);  // validates p and o
  return run_twin_with(p, smoother, s);
}

}  // namespace implicit::da
