#pragma once
// A twin experiment: a truth run of the problem's model, observations of it drawn with the seed,
// one ensemble filter (or the implicit smoother) assimilating them, and the scores of the analysis
// (docs/specification.md, "Data assimilation"):
//
//   rmse.a   = mean over scored cycles k of sqrt(|xbar_a(k) - x_true(k)|^2 / n)
//   spread.a = mean over scored cycles of the analysis spread (filters.hpp)
//
// with the cycles at times t_k = k * interval scored when t_k > burn_in.
//
//   implicit::da::TwinSettings s{.cycles = 1000, .interval = 0.25, .burn_in = 4.0,
//                                .truth0 = x0, .mean0 = x0, .cov0 = 2 I, .seed = 3};
//   const auto r = implicit::da::run_twin(problem, options, s);   // r.rmse_a, r.spread_a
//
// Streams: observation noise (seed, k, 0, kData), truth model noise of the i-th interval
// (i = 0..K-1, K = steps_per_observation) before observation k (seed, k, 1 + i, kData) when the
// model is stochastic; the filter's own streams are keyed by the same seed with other purposes.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "implicit/da/filters.hpp"
#include "implicit/da/smoother.hpp"

namespace implicit::da {

struct TwinSettings {
  int cycles = 100;        ///< observation cycles
  double interval = 1.0;   ///< model time per cycle (from one observation to the next)
  double burn_in = 0.0;    ///< cycles at times <= burn_in are not scored
  Eigen::VectorXd truth0;  ///< the truth at time 0
  Eigen::VectorXd mean0;   ///< initial ensemble N(mean0, cov0)
  Eigen::MatrixXd cov0;
  std::uint64_t seed = 1;
  bool keep_history = false;  ///< keep the truths and analysis means of every cycle
};

struct TwinResult {
  double rmse_a = 0.0;
  double spread_a = 0.0;
  double mean_ess = 0.0;  ///< mean over scored cycles of the analysis N_eff
  int scored_cycles = 0;
  int resamplings = 0;
  long sampling_failures = 0;  ///< implicit: member-cycles with weight 0 from a failed sample
  double ms_per_cycle = 0.0;   ///< wall time of the filter (forecast + analysis) per cycle
  /// The first cycle whose analysis mean is not finite (the filter diverged; 0: none). The run
  /// stops there and its scores are NaN: a mean over the cycles before would not be a result.
  int diverged_at = 0;
  std::vector<Eigen::VectorXd> truth, means;  ///< cycles 1..K (keep_history)
};

/// Runs the twin experiment; throws InvalidArgument for cycles < 1, a non-positive interval, a
/// negative or NaN burn-in, a burn-in that leaves no cycle to score, wrong sizes, or a truth
/// that leaves the finite numbers (a model unstable at its settings). A filter that diverges is
/// an outcome, not an error: see TwinResult::diverged_at.
TwinResult run_twin(const Problem& p, const FilterOptions& o, const TwinSettings& s);
/// The same twin experiment with the implicit smoother (smoother.hpp): the analysis scored at
/// each cycle is its filtering analysis at the observation's time.
TwinResult run_twin(const Problem& p, const SmootherOptions& o, const TwinSettings& s);

/// rmse.a of analysis means against truths (same length), over the entries from `first` on.
double analysis_rmse(std::span<const Eigen::VectorXd> means, std::span<const Eigen::VectorXd> truth,
                     std::size_t first);

}  // namespace implicit::da
