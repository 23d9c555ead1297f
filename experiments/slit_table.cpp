#include "experiments/slit_table.hpp"

#include <cmath>
#include <utility>

#include "experiments/run_statistics.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"

namespace implicit::experiments {

control::EstimatorOptions slit_estimator_options(control::SlitEstimator estimator, int samples) {
  control::EstimatorOptions o;
  o.samples = samples;
  o.fd_step = 1e-3;
  o.relative_fd_step = false;
  o.modes = control::ModeSampling::kEachMode;
  o.freeze_walls = estimator == control::SlitEstimator::kFrozenWall;
  if (estimator == control::SlitEstimator::kPaper) {
    o.modes = control::ModeSampling::kDominant;
    o.laplace_weights = true;
  }
  return o;
}

control::SlitRun generic_slit_run(const control::DoubleSlit& slit,
                                  const control::DoubleSlitProblem& problem,
                                  const control::EstimatorOptions& options, std::uint64_t seed,
                                  std::uint64_t run) {
  const auto& p = slit.parameters();
  const int K = slit.num_steps(), K1 = slit.wall_step();
  Eigen::MatrixXd W(1, K);
  Rng rng({seed, run, 0, purpose::kProcessNoise});
  rng.fill_normal(W);
  const auto loop =
      control::simulate_closed_loop(problem, Vec<1>(p.initial_state), W, options, seed, run);
  control::SlitRun r;
  r.x_exact.resize(K + 1);
  r.x_estimate.resize(K + 1);
  r.u_exact.resize(K);
  r.u_estimate.resize(K);
  r.x_exact(0) = p.initial_state;
  const double sd = std::sqrt(p.sigma * p.dt);
  double ess_sum = 0.0;
  for (int k = 0; k < K; ++k) {
    r.u_exact(k) = slit.exact_control(r.x_exact(k), slit.time(k));
    r.x_exact(k + 1) = r.x_exact(k) + r.u_exact(k) * p.dt + sd * W(0, k);
    r.u_estimate(k) = loop.u[static_cast<std::size_t>(k)](0);
    if (k < K1) ess_sum += loop.psi[static_cast<std::size_t>(k)].ess;
  }
  for (int k = 0; k <= K; ++k) r.x_estimate(k) = loop.x[static_cast<std::size_t>(k)](0);
  r.fallbacks = loop.fallbacks;
  control::score_slit_run(slit, r);
  r.ess_mean = ess_sum / K1;
  return r;
}

control::SlitRun slit_run(const control::DoubleSlit& slit, const SlitTableOptions& o,
                          std::uint64_t run) {
  if (o.implementation == SlitImplementation::kWallSpace)
    return control::simulate_slit_run(slit, o.samples, o.estimator, o.seed, run, o.sampling);
  // Exact for the double slit (no drift, no running cost) and 2-D: PathGrid's note.
  const auto problem =
      control::double_slit_problem(slit.parameters(), control::PathGrid::kWallsAndHorizon);
  return generic_slit_run(slit, problem, slit_estimator_options(o.estimator, o.samples), o.seed,
                          run);
}

SlitTableRow slit_table_row(const control::DoubleSlit& slit, const SlitTableOptions& o,
                            std::uint64_t run) {
  const control::SlitRun r = slit_run(slit, o, run);
  SlitTableRow row;
  row.error_x = r.error_x;
  row.error_u = r.error_u;
  row.crashed_exact = r.crashed_exact;
  row.crashed_estimate = r.crashed_estimate;
  row.fallbacks = r.fallbacks;
  row.ess_mean = r.ess_mean;
  return row;
}

SlitTable summarise_slit_table(std::vector<SlitTableRow> rows) {
  require(!rows.empty(), "double slit table: expected at least 1 run, got 0");
  SlitTable t;
  t.runs = std::move(rows);
  std::vector<double> ex, eu;
  for (const auto& row : t.runs) {
    ex.push_back(row.error_x);
    eu.push_back(row.error_u);
    t.crash_fraction += row.crashed_estimate ? 1.0 : 0.0;
    t.exact_crash_fraction += row.crashed_exact ? 1.0 : 0.0;
    t.fallbacks += row.fallbacks;
    t.ess_mean += row.ess_mean;
  }
  const double R = static_cast<double>(t.runs.size());
  t.crash_fraction /= R;
  t.exact_crash_fraction /= R;
  t.ess_mean /= R;
  t.error_x_mean = mean_of(ex);
  t.error_x_std = sd_of(ex);
  t.error_x_median = median_of(ex);
  t.error_u_mean = mean_of(eu);
  t.error_u_std = sd_of(eu);
  t.error_u_median = median_of(eu);
  return t;
}

SlitTable run_slit_table(const control::DoubleSlit& slit, const SlitTableOptions& o) {
  require(o.runs >= 1, "double slit table: expected at least 1 run, got {}", o.runs);
  require(o.samples >= 1, "double slit table: expected at least 1 sample, got {}", o.samples);
  std::vector<SlitTableRow> rows(static_cast<std::size_t>(o.runs));
  parallel_for(
      rows.size(), [&](std::size_t r) { rows[r] = slit_table_row(slit, o, r); }, 1);
  return summarise_slit_table(std::move(rows));
}

}  // namespace implicit::experiments
