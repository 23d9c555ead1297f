#pragma once
// Data assimilation benchmarks (`implicit da`): one filter on the Lorenz-63 setting `sakov2012`
// or the Lorenz-96 setting `bocquet2010`, over several seeds, scored by rmse.a with a 95 %
// confidence interval (docs/cli.md, docs/specification.md "Data assimilation"). The settings
// are reproduced from the DAPPER benchmark tables, whose published rmse.a values are in
// data/da/dapper_benchmarks.json.

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "experiments/run_context.hpp"
#include "implicit/da/twin.hpp"

namespace implicit::experiments {

struct DaSettings {
  std::string model = "lorenz63";  ///< lorenz63 (sakov2012) or lorenz96 (bocquet2010)
  int dim = 10;                    ///< Lorenz-96 dimension (>= 4)
  double forcing = 8.0;            ///< Lorenz-96 forcing F
  std::string method = "etkf";     ///< bootstrap, implicit, enkf, etkf or implicit-smoother
  int members = 10;
  int seeds = 10;  ///< independent runs: seeds ctx.seed, ctx.seed + 1, ...
  double jitter = 0.0;
  std::string regularisation = "iso";  ///< particle filters: iso or cov (filters.hpp)
  double inflation = 1.0;
  double resample_threshold = 0.5;
  std::string map = "linear";  ///< implicit filter: linear or random map
  int cycles = 0;              ///< observation cycles; 0: the setting's own (1000 or 1280)
  int lag = 0;  ///< implicit-smoother: window length L in cycles (0: kDefaultLag); others: 0
  /// implicit-smoother: Newton starts per window (0: kDefaultStarts); others: 0.
  int starts = 0;
  /// implicit-smoother: kernel bandwidth h in (0, 1] (1: one Gaussian background); others: 1.
  double bandwidth = 1.0;
  /// K: model intervals per observation (the setting's interval each; 1: the setting's own).
  int obs_every = 1;
  /// q: std of the model noise N(0, q^2 I) added after every interval (0: deterministic).
  double model_noise = 0.0;
};

/// The implicit smoother's window length when --lag is not given.
inline constexpr int kDefaultLag = 3;
/// The implicit smoother's Newton starts when --starts is not given (da::SmootherOptions).
inline constexpr int kDefaultStarts = 3;

/// The problem and twin settings of a benchmark setting for `seed` (the Lorenz-96 truth starts
/// from a state spun up from F + N(0, 1) noise drawn with the seed). Lorenz-96 with n != 10 or
/// F != 8 is named "bocquet2010-n<n>" and/or "-F<F>" (bocquet2010 is n = 10, F = 8). With obs_every
/// K > 1 or a model noise q > 0 (the variant where implicit and optimal-proposal sampling differ),
/// the setting observes after every K-th interval, adds N(0, q^2 I) after every interval, runs the
/// same model time (the setting's cycles / K, rounded up) and is named "<setting>-k<K>-q<q>".
/// Throws InvalidArgument for an unknown model, a dimension below 4, a non-finite forcing, K < 1
/// or a negative or non-finite q.
struct DaSetup {
  da::Problem problem;
  da::TwinSettings twin;
  std::string setting;  ///< sakov2012 or bocquet2010, or the variant's name
};
DaSetup da_setup(const DaSettings& s, std::uint64_t seed);

/// Keys: model, setting, dim, method, members, seeds, seed, jitter, regularisation, inflation,
/// resample_threshold, map, lag, starts and bandwidth (implicit-smoother; null otherwise),
/// obs_every, model_noise, cycles, burn_in, rmse_a {mean, sd, ci95 [lo, hi]}, spread_a, mean_ess,
/// ms_per_cycle, resamplings_per_run, sampling_failures, diverged_runs, runs [{seed, rmse_a,
/// spread_a, mean_ess, ms_per_cycle, diverged_at_cycle}], threads, seconds. A run whose filter
/// diverged (TwinResult::diverged_at) has NaN scores (null in JSON), and so has the summary.
nlohmann::json run_da(const DaSettings& s, const RunContext& ctx);

/// The 0.975 quantile of Student's t with `df` degrees of freedom (df >= 1).
double student_t975(int df);

}  // namespace implicit::experiments
