// When does the implicit proposal pay? Implicit and bootstrap MCL (spec §3.3-3.4) on simulated
// unicycle logs, against (a) the ratio of the per-step process noise to the sensor noise and
// (b) the motion step length, with the Car Park's noise ratio for configs A and B as real points.
//
// Each run simulates one log and runs both proposals on it with the same filter seed, so the two
// columns of a point are paired: their difference has a smaller spread than either alone.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "experiments/parallel_runs.hpp"
#include "experiments/proposal_gain.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/carpark.hpp"
#include "implicit/robot/simulate.hpp"

namespace implicit::experiments {
namespace {

/// One point of a sweep: the step length and the sensor noise.
struct GainPoint {
  std::string sweep;  ///< "ratio" or "dt"
  double dt = 0.1;
  double range_sd = 0.1;     ///< [m]
  double bearing_sd = 0.01;  ///< [rad]
  double ratio = 0.0;        ///< per-step process position sd / range sd
};

// The route is driven at 1 m/s; bearing noise is the range noise seen at 10 m, so one number
// (range_sd) sets the sensor's scale.
constexpr double kBearingPerRange = 0.1;  // [rad/m]
constexpr double kScanPeriod = 0.4;       // [s] between scans, whatever the step length

/// Per-axis position sd of one unicycle step: sqrt(trace of the position block of Sigma1 / 2).
double step_position_sd(const robot::UnicycleParams& p) {
  const double v = p.control_std(0), q1 = p.state_std(0), q2 = p.state_std(1);
  return std::sqrt(p.dt * (v * v + q1 * q1 + q2 * q2) / 2.0);
}

std::vector<GainPoint> make_points(const ProposalGainSettings& s) {
  std::vector<GainPoint> points;
  robot::UnicycleParams base;
  base.dt = s.ratio_dt;
  const double sp = step_position_sd(base);
  for (double r : s.ratios)
    points.push_back({"ratio", s.ratio_dt, sp / r, kBearingPerRange * sp / r, r});
  for (double dt : s.dts) {
    robot::UnicycleParams p;
    p.dt = dt;
    points.push_back({"dt", dt, s.dt_range_sd, kBearingPerRange * s.dt_range_sd,
                      step_position_sd(p) / s.dt_range_sd});
  }
  return points;
}

/// Both proposals on one simulated log.
ProposalGainRunRecord gain_run(const GainPoint& pt, const ProposalGainSettings& s,
                               std::uint64_t seed) {
  robot::UnicycleParams params;
  params.dt = pt.dt;
  const robot::UnicycleModel model(params);
  const auto sensor = robot::RangeBearingSensor::from_std(pt.range_sd, pt.bearing_sd);
  robot::SimulationOptions o;
  o.steps = std::max(1, static_cast<int>(std::lround(s.duration / pt.dt)));
  o.scan_every = std::max(1, static_cast<int>(std::lround(kScanPeriod / pt.dt)));
  const robot::RobotLog log = robot::simulate_robot_log(
      model, sensor, robot::square_route_driver(1.0, o.route_side, true), o, seed);
  const filter::LocalizationProblem problem = filter::make_problem(log, model.dt());
  filter::FilterOptions fo;
  fo.particles = static_cast<std::size_t>(s.particles);
  fo.seed = seed;
  ProposalGainRunRecord rec;
  auto add = [&](const filter::LocalizationRun& run, double& ess, double& rmse, double& cpu) {
    const auto m = filter::localization_metrics(run, problem.truth, fo.particles);
    ess = m.ess_fraction;
    rmse = m.rmse;
    cpu = 1e3 * run.cpu_seconds / static_cast<double>(run.steps.size());
  };
  add(filter::run_localization(problem, model, sensor, filter::ImplicitProposal{}, fo),
      rec.implicit_ess, rec.implicit_rmse_m, rec.implicit_cpu_ms_per_step);
  add(filter::run_localization(problem, model, sensor, filter::BootstrapProposal{}, fo),
      rec.standard_ess, rec.standard_rmse_m, rec.standard_cpu_ms_per_step);
  return rec;
}

using GainField = double ProposalGainRunRecord::*;

/// Mean and standard error (sd / sqrt(n)) of field `k` of the records, less field `k_minus`.
std::pair<double, double> paired_mean_se(const std::vector<ProposalGainRunRecord>& recs,
                                         GainField k, GainField k_minus = nullptr) {
  std::vector<double> v;
  for (const auto& r : recs) v.push_back(r.*k - (k_minus == nullptr ? 0.0 : r.*k_minus));
  const double n = static_cast<double>(v.size());
  const double m = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0.0;
  for (double x : v) ss += (x - m) * (x - m);
  return {m, v.size() > 1 ? std::sqrt(ss / (n - 1.0) / n) : 0.0};
}

/// The Car Park's per-step process position sd against its range sd, for P = diag(p, p): the
/// variance averaged over the dead-reckoned steps of the bundled log (no filter is run).
double carpark_ratio(double p) {
  robot::UteParams params;
  params.control_std = Vec<2>(p, p);
  const robot::UteModel model(params);
  const robot::RobotLog log =
      robot::carpark_to_log(robot::load_carpark(robot::default_carpark_dir()), model);
  const filter::LocalizationProblem problem = filter::make_problem(log, model.dt());
  robot::Pose x = problem.initial_mean;
  double sum = 0.0;
  const std::size_t n = problem.schedule.steps.size();
  for (std::size_t k = 0; k < n; ++k) {
    const auto step = model.with_dt(problem.step_dt[k]);
    const auto& u = problem.schedule.steps[k].u;
    const robot::Mat3 c = step.process_covariance(x, u);
    sum += (c(0, 0) + c(1, 1)) / 2.0;
    x = step.predict(x, u);
  }
  const double range_sd = std::sqrt(robot::RangeBearingSensor().noise_covariance()(0, 0));
  return std::sqrt(sum / static_cast<double>(n)) / range_sd;
}

nlohmann::json point_json(const GainPoint& pt, const std::vector<ProposalGainRunRecord>& recs) {
  nlohmann::json j{{"sweep", pt.sweep},
                   {"dt", pt.dt},
                   {"range_sd", pt.range_sd},
                   {"bearing_sd", pt.bearing_sd},
                   {"ratio", pt.ratio}};
  using R = ProposalGainRunRecord;
  const char* names[] = {"ess", "rmse_m", "cpu_ms_per_step"};
  const GainField implicit[] = {&R::implicit_ess, &R::implicit_rmse_m,
                                &R::implicit_cpu_ms_per_step};
  const GainField standard[] = {&R::standard_ess, &R::standard_rmse_m,
                                &R::standard_cpu_ms_per_step};
  for (const auto* fields : {implicit, standard}) {
    nlohmann::json c;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto [mean, se] = paired_mean_se(recs, fields[k]);
      c[names[k]] = mean;
      c[std::string(names[k]) + "_se"] = se;
    }
    j[fields == implicit ? "implicit" : "standard"] = c;
  }
  // Paired differences, implicit minus bootstrap, over the same logs and seeds.
  for (std::size_t k = 0; k < 3; ++k) {
    const auto [mean, se] = paired_mean_se(recs, implicit[k], standard[k]);
    j["diff"][names[k]] = mean;
    j["diff"][std::string(names[k]) + "_se"] = se;
  }
  return j;
}

void write_csv(const RunContext& ctx, const nlohmann::json& points) {
  OutputFile output(ctx.csv_path("proposal_gain.csv"));
  std::ostream& out = output.stream();
  out << "sweep,dt,range_sd,ratio,method,ess,ess_se,rmse_m,rmse_m_se,cpu_ms_per_step,"
         "cpu_ms_per_step_se\n";
  for (const auto& p : points)
    for (const char* m : {"implicit", "standard"}) {
      const auto& c = p[m];
      out << fmt::format("{},{},{:.6g},{:.6g},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n",
                         p["sweep"].get<std::string>(), p["dt"].get<double>(),
                         p["range_sd"].get<double>(), p["ratio"].get<double>(), m,
                         c["ess"].get<double>(), c["ess_se"].get<double>(),
                         c["rmse_m"].get<double>(), c["rmse_m_se"].get<double>(),
                         c["cpu_ms_per_step"].get<double>(), c["cpu_ms_per_step_se"].get<double>());
    }
  output.commit();
}

}  // namespace

nlohmann::json run_proposal_gain(const ProposalGainSettings& s, const RunContext& ctx) {
  require(s.particles >= 1, "proposal-gain --particles: expected >= 1, got {}", s.particles);
  require(s.runs >= 1, "proposal-gain --runs: expected >= 1, got {}", s.runs);
  require(s.duration > 0, "proposal-gain --duration: expected > 0, got {}", s.duration);
  require(s.dt_range_sd > 0, "proposal-gain --dt-range-sd: expected > 0, got {}", s.dt_range_sd);
  for (double r : s.ratios) require(r > 0, "proposal-gain --ratios: expected > 0, got {}", r);
  for (double d : s.dts) require(d > 0, "proposal-gain --dts: expected > 0, got {}", d);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<GainPoint> points = make_points(s);
  const std::size_t runs = static_cast<std::size_t>(s.runs);
  const std::string settings = fmt::format(
      "seed={} M={} runs={} duration={:a} ratio_dt={:a} dt_range_sd={:a} ratios={:a} dts={:a}",
      ctx.seed, s.particles, s.runs, s.duration, s.ratio_dt, s.dt_range_sd,
      fmt::join(s.ratios, ","), fmt::join(s.dts, ","));
  ProgressBar bar("proposal-gain", points.size() * runs, ctx.show_progress());
  // Run i is point i / runs, replicate i % runs; its seed depends on nothing else, so every
  // thread count gives the same records.
  const auto records =
      distribute_runs(ctx, "proposal_gain", settings, points.size() * runs, [&](std::size_t i) {
        const std::uint64_t seed = ctx.seed * 1000003ull + static_cast<std::uint64_t>(i);
        const ProposalGainRunRecord r = gain_run(points[i / runs], s, seed);
        bar.tick();
        return r;
      });
  bar.finish();
  nlohmann::json j;
  j["particles"] = s.particles;
  j["runs"] = s.runs;
  j["duration_s"] = s.duration;
  j["scan_period_s"] = kScanPeriod;
  j["seed"] = ctx.seed;
  j["threads"] = active_threads();
  j["points"] = nlohmann::json::array();
  for (std::size_t p = 0; p < points.size(); ++p) {
    const std::vector<ProposalGainRunRecord> recs(
        records.begin() + static_cast<std::ptrdiff_t>(p * runs),
        records.begin() + static_cast<std::ptrdiff_t>((p + 1) * runs));
    j["points"].push_back(point_json(points[p], recs));
  }
  try {
    j["carpark_ratio"] = {{"A", carpark_ratio(0.5)}, {"B", carpark_ratio(0.1)}};
  } catch (const std::exception& e) {
    j["carpark_ratio_error"] = e.what();  // no bundled data: the simulated sweeps still count
  }
  if (!ctx.out_dir.empty() && rank_index() == 0) write_csv(ctx, j["points"]);
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return j;
}

}  // namespace implicit::experiments
