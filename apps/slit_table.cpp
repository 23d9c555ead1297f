#include "slit_table.hpp"

#include <utility>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "run_statistics.hpp"

namespace implicit::app {

SlitTableRow slit_table_row(const control::DoubleSlit& slit, const SlitTableOptions& o,
                            std::uint64_t run) {
  const control::SlitRun r =
      control::simulate_slit_run(slit, o.samples, o.estimator, o.seed, run, o.sampling);
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

}  // namespace implicit::app
