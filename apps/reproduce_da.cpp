// The da experiment of `implicit reproduce` (beyond the paper): data assimilation on Lorenz-63
// (DAPPER's sakov2012) and Lorenz-96 (bocquet2010) with the tuned settings of docs/cli.md's
// table, each beside DAPPER's published rmse.a for the same filter and N
// (data/da/dapper_benchmarks.json). The runs are experiments/da.hpp's; this file only lays out
// the plan and attaches DAPPER's number.
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "experiments/da.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/share_dir.hpp"
#include "reproduce_plan.hpp"

namespace implicit::app {
namespace {

using nlohmann::json;

/// One row of the table: a method with its tuning (docs/cli.md, "implicit da").
struct DaRow {
  const char* model;
  const char* method;
  int members;
  double jitter = 0.0;
  double inflation = 1.0;
  double resample_threshold = 0.5;
  const char* regularisation = "iso";
  int lag = 0;
  int seeds = 10;
  int obs_every = 1;         ///< the variant: intervals per observation ...
  double model_noise = 0.0;  ///< ... and the model noise std q after each
  double bandwidth = 1.0;    ///< implicit-smoother: kernel bandwidth h (1: Gaussian background)
};

// The measuring seeds of docs/cli.md's table are 101-110 for the tool's default --seed 1 (the
// tuning used seeds 1-5): the runs start at seed + kSeedOffset.
constexpr std::uint64_t kSeedOffset = 100;

const std::vector<DaRow>& rows() {
  static const std::vector<DaRow> r = {
      {"lorenz63", "etkf", 10, 0.0, 1.1},
      {"lorenz63", "enkf", 100},
      {"lorenz63", "bootstrap", 100, 0.2, 1.0, 0.8},
      {"lorenz63", "bootstrap", 800, 0.07},
      {"lorenz63", "bootstrap", 4000, 0.05, 1.0, 0.5, "iso", 0, 5},
      {"lorenz63", "implicit", 10, 1.5},
      {"lorenz63", "implicit", 100, 0.5},
      {"lorenz63", "implicit-smoother", 10, 0.0, 1.2, 0.5, "iso", 3},
      {"lorenz63", "implicit-smoother", 30, 0.0, 1.0, 0.5, "iso", 4},
      {"lorenz63", "implicit-smoother", 100, 0.0, 1.0, 0.5, "iso", 3},
      {"lorenz63", "implicit-smoother", 100, 0.0, 1.03, 0.5, "iso", 3, 10, 1, 0.0, 0.6},
      {"lorenz96", "etkf", 10, 0.0, 1.05},
      {"lorenz96", "bootstrap", 100, 1.0, 1.0, 0.4, "cov"},
      {"lorenz96", "bootstrap", 800, 0.2},
      {"lorenz96", "implicit", 100, 0.3},
      {"lorenz96", "implicit-smoother", 100, 0.0, 1.03, 0.5, "iso", 8},
      // The variant bocquet2010-k4-q0.5: model noise, observed after every 4th interval, where
      // implicit and optimal-proposal sampling differ (no tuning: the noise keeps members apart).
      {"lorenz96", "bootstrap", 100, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "bootstrap", 800, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "bootstrap", 3000, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "implicit", 30, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "implicit", 100, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "implicit", 300, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5},
      {"lorenz96", "enkf", 100, 0.0, 1.0, 0.5, "iso", 0, 10, 4, 0.5}};
  return r;
}

experiments::DaSettings settings_of(const DaRow& r, bool quick);

/// sakov2012, bocquet2010 or the variant's name (experiments::da_setup).
std::string setting_of(const DaRow& r) {
  return experiments::da_setup(settings_of(r, false), 1).setting;
}

/// DAPPER's rmse.a for this setting, method and N, if it lists one.
std::optional<double> dapper_rmse(const DaRow& r) {
  const auto file = find_share_dir("data", "IMPLICIT_DATA_DIR") / "da" / "dapper_benchmarks.json";
  std::ifstream in(file);
  require(in.good(), "da: cannot read DAPPER's table {}", file.string());
  json t;
  try {
    t = json::parse(in);
  } catch (const json::exception& e) {
    throw InvalidArgument(fmt::format("da: {} is not DAPPER's table: {}", file.string(), e.what()));
  }
  for (const auto& row : t.value("rows", json::array()))
    if (row.is_array() && row.size() == 5 && row[0] == setting_of(r) && row[2] == r.method &&
        row[3] == r.members && row[4].is_number())
      return row[4].get<double>();
  return std::nullopt;
}

experiments::DaSettings settings_of(const DaRow& r, bool quick) {
  experiments::DaSettings s;
  s.model = r.model;
  s.method = r.method;
  s.members = r.members;
  s.jitter = r.jitter;
  s.inflation = r.inflation;
  s.resample_threshold = r.resample_threshold;
  s.regularisation = r.regularisation;
  s.lag = r.lag;
  s.seeds = quick ? 2 : r.seeds;
  s.obs_every = r.obs_every;
  s.model_noise = r.model_noise;
  s.bandwidth = r.bandwidth;
  // Quick: past the burn-in (16 cycles of Lorenz-63, 400 of Lorenz-96; K times fewer for the
  // variant) and a little beyond.
  const int quick_cycles = std::string(r.model) == "lorenz63" ? 100 : 500;
  s.cycles = quick ? (quick_cycles + r.obs_every - 1) / r.obs_every : 0;
  return s;
}

json run_row(const DaRow& row, bool quick, const RunContext& ctx) {
  RunContext c = ctx;
  c.seed = ctx.seed + kSeedOffset;
  c.out_dir.clear();  // the runner writes no files; the figure reads the table CSV
  json j = experiments::run_da(settings_of(row, quick), c);
  require(j.at("diverged_runs") == 0,
          "da: {} of {} runs diverged (the analysis mean left the finite numbers): rmse.a is not "
          "defined",
          j.at("diverged_runs").get<int>(), j.at("seeds").get<int>());
  // Flat keys for the table CSV and the figure (rmse_a keeps its object).
  const json& rmse = j.at("rmse_a");
  j["rmse_a_mean"] = rmse.at("mean");
  j["rmse_a_lo"] = rmse.at("ci95").is_array() ? rmse.at("ci95")[0] : json(nullptr);
  j["rmse_a_hi"] = rmse.at("ci95").is_array() ? rmse.at("ci95")[1] : json(nullptr);
  const auto dapper = dapper_rmse(row);
  j["dapper_rmse_a"] = dapper ? json(*dapper) : json(nullptr);
  return j;
}

}  // namespace

// Cost, measured (docs/reproducing.md, "Run times"): the whole table about 15 s on 2 cores
// before the variant's rows, which add about 75 s (the implicit filter's paths).
void add_da(Plan& plan, bool quick) {
  json configurations = json::array();
  for (const DaRow& row : rows()) {
    if (quick && row.members > 100) continue;
    const experiments::DaSettings s = settings_of(row, quick);
    const json settings = {
        {"model", s.model},
        {"setting", setting_of(row)},
        {"method", s.method},
        {"members", s.members},
        {"jitter", s.jitter},
        {"inflation", s.inflation},
        {"resample_threshold", s.resample_threshold},
        {"regularisation", s.regularisation},
        {"lag", s.lag == 0 ? json(nullptr) : json(s.lag)},
        {"bandwidth", s.method == "implicit-smoother" ? json(s.bandwidth) : json(nullptr)},
        {"obs_every", s.obs_every},
        {"model_noise", s.model_noise},
        {"seeds", s.seeds},
        {"cycles", s.cycles}};
    configurations.push_back(settings);
    // Rough CPU seconds: about 3 us per member and cycle, 1000 cycles of Lorenz-63 or 1280 of
    // Lorenz-96 (quick: 100 or 500), times K for the variant's K intervals per cycle; the implicit
    // filter's paths (Newton over 4 x 10 noises) about 200 us, the smoother's kernels (a Newton
    // run per member) about 80 us.
    const double cycles = s.cycles > 0 ? s.cycles : 1000.0;
    const double per_member = std::string(row.method) == "implicit" && row.obs_every > 1 ? 2e-4
                              : row.bandwidth < 1.0                                      ? 8e-5
                                                                                         : 3e-6;
    plan.configs.push_back(
        {"da",
         fmt::format("da {}{} {}{} N={}", s.model, row.obs_every > 1 ? " (variant)" : "", s.method,
                     row.bandwidth < 1.0 ? fmt::format(" h={}", row.bandwidth) : "", s.members),
         settings, per_member * s.members * cycles * s.seeds, false,
         [row, quick](const RunContext& ctx) { return run_row(row, quick, ctx); }});
  }
  plan.settings["da"] = {
      {"configurations", configurations},
      {"seeds", fmt::format("seed + {} onwards (101-110 for --seed 1; tuned on 1-5)", kSeedOffset)},
      {"dapper", "data/da/dapper_benchmarks.json"}};
}

}  // namespace implicit::app
