// Global localization and kidnapping on a robot log (spec §3.11): `implicit mcl --init global`
// and `implicit mcl --kidnap-at T --kidnap-skip D`, with recovery and KLD-sampling.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "experiments/landmark_mcl_global.hpp"
#include "experiments/parallel_runs.hpp"
#include "experiments/run_context.hpp"
#include "experiments/run_statistics.hpp"
#include "implicit/core/error.hpp"
#include "implicit/filter/global_run.hpp"

namespace implicit::experiments {

void check_global_settings(const MclSettings& s) {
  require(s.init == "known" || s.init == "global", "mcl --init: expected known or global, got '{}'",
          s.init);
  require(s.recovery == "auto" || s.recovery == "none" || s.recovery == "uniform" ||
              s.recovery == "mixture",
          "mcl --recovery: expected auto, none, uniform or mixture, got '{}'", s.recovery);
  require(s.start_span >= 0 && std::isfinite(s.start_span),
          "mcl --start-span: expected a finite value >= 0, got {}", s.start_span);
  require(s.kidnap_at < 0 || s.kidnap_skip > 0,
          "mcl --kidnap-skip: expected a positive duration, got {}", s.kidnap_skip);
  require(s.kidnap_at < 0 || s.init == "known",
          "mcl --kidnap-at: kidnapping runs start from the known pose; drop --init global");
  require(s.truth == MclTruth::kGps,
          "mcl --init global / --kidnap-at: expected --truth gps, got '{}'", name_of(s.truth));
}

namespace {

/// The source of the first particles and of recovery: uniform for the standard (bootstrap)
/// method, the mixture over the minima for implicit, unless --recovery names one.
filter::GlobalSource source_of(const MclSettings& s) {
  if (s.recovery == "uniform") return filter::GlobalSource::kUniform;
  if (s.recovery == "mixture") return filter::GlobalSource::kMixture;
  return s.method == "implicit" ? filter::GlobalSource::kMixture : filter::GlobalSource::kUniform;
}

/// Per step with truth, the position error of the first `count` runs (Figure 9's data): time
/// relative to the log's first control t0, the run's start (from t0) and its particle count.
using RunNumber = std::function<std::pair<filter::LocalizationRun, double>(std::size_t)>;
void write_errors(const std::filesystem::path& file, const filter::LocalizationProblem& problem,
                  double t0, std::size_t count, const RunNumber& run_number) {
  OutputFile out(file);
  out.print("run,start_s,time_s,error_m,particles\n");
  const auto& steps = problem.schedule.steps;
  for (std::size_t r = 0; r < count; ++r) {
    const auto [run, from] = run_number(r);
    for (std::size_t k = 0; k < run.steps.size(); ++k) {
      const std::size_t step = run.first_step + k;
      const Vec<2>& truth = problem.truth.position[step];
      if (!truth.allFinite()) continue;
      const double e = (run.steps[k].mean.head<2>() - truth).norm();
      out.print("{},{:.3f},{:.3f},{:.6g},{}\n", r, from - t0, steps[step].time - t0, e,
                run.steps[k].particles);
    }
  }
  out.commit();
}

/// Why the test of these settings cannot happen on `problem` (the log cut to --duration), or ""
/// when it can: a kidnapping at or after the log's end, nothing left after its gap, or no step
/// with ground truth to score. A rate of 0 for a test that never happened would read as a
/// filter that never recovers.
std::string empty_test(const MclSettings& s, const filter::LocalizationProblem& problem,
                       double t0) {
  const auto& steps = problem.schedule.steps;
  const double end = steps.back().time - t0;
  const bool kidnap = s.kidnap_at >= 0;
  if (kidnap && s.kidnap_at >= end)
    return fmt::format(
        "mcl --kidnap-at {}: expected a time before the log's end ({:.3f} s after its first "
        "control), got one after it: the kidnapping never happens",
        s.kidnap_at, end);
  const double from = kidnap ? s.kidnap_at + s.kidnap_skip : 0.0;
  if (kidnap && from >= end)
    return fmt::format(
        "mcl --kidnap-at {} --kidnap-skip {}: expected steps after the gap, got the log's end "
        "({:.3f} s after its first control) inside it: nothing is left to recover on",
        s.kidnap_at, s.kidnap_skip, end);
  for (std::size_t k = 0; k < steps.size(); ++k)
    if (steps[k].time - t0 >= from && problem.truth.position[k].allFinite()) return "";
  return fmt::format(
      "mcl {}: expected ground truth ('truth' records) {} to score the runs, got none",
      kidnap ? "--kidnap-at" : "--init global",
      kidnap ? "after the kidnapping's gap" : "in the log");
}

template <typename Motion>
nlohmann::json run_global(const MclSettings& s, const RunContext& ctx, const Motion& model,
                          const robot::RangeBearingSensor& sensor,
                          const filter::LocalizationProblem& full) {
  check_global_settings(s);
  const bool kidnap = s.kidnap_at >= 0;
  const double t0 = full.schedule.steps.front().time;
  // --duration: every run ends at t0 + duration (measured from the first control, not from a
  // run's start), so the runs of a study see the same end of the log.
  const filter::LocalizationProblem cut =
      s.duration > 0
          ? filter::without_steps(full, t0 + s.duration, std::numeric_limits<double>::infinity())
          : full;
  const std::string empty = empty_test(s, cut, t0);
  if (!empty.empty()) {
    require(s.allow_empty,
            "{}; --allow-empty runs it anyway (exit 0, the JSON's \"empty\" says why)", empty);
    fmt::print(stderr, "implicit mcl: warning: {} (allowed by --allow-empty)\n", empty);
  }
  // Kidnapping: the steps of [T, T + D) are never seen (filter/localization.hpp, without_steps).
  const filter::LocalizationProblem problem =
      kidnap ? filter::without_steps(cut, t0 + s.kidnap_at, t0 + s.kidnap_at + s.kidnap_skip) : cut;
  filter::FilterOptions options;
  options.particles = static_cast<std::size_t>(s.particles);
  options.association.clutter = s.clutter;
  options.association.label_gate = s.label_gate;
  options.kld.enabled = s.kld;
  options.kld.kld_err = s.kld_err;
  options.kld.kld_z = s.kld_z;
  options.kld.min_particles = static_cast<std::size_t>(s.min_particles);
  options.kld.max_particles = static_cast<std::size_t>(s.max_particles);
  // A global start under KLD begins with the most particles it may use, as AMCL does.
  if (s.kld && s.init == "global") options.particles = options.kld.max_particles;
  const bool recover = s.recovery == "auto" ? (kidnap || s.init == "global") : s.recovery != "none";
  options.recovery.enabled = recover;
  options.recovery.recovery_alpha_slow = s.recovery_alpha_slow;
  options.recovery.recovery_alpha_fast = s.recovery_alpha_fast;
  options.recovery.kidnap_probability = s.kidnap_probability;
  // Checked once, before the runs: the filter of each run checks them too, but a refusal there
  // reads "N of N runs failed" (a RuntimeError in Python) instead of an invalid setting.
  if (options.kld.enabled) filter::validate(options.kld);
  if (options.recovery.enabled) filter::validate(options.recovery);
  filter::GlobalOptions g;
  g.source = source_of(s);
  g.init.cover_spacing = s.cover_spacing;
  g.init.cover_headings = s.cover_headings;
  g.global_start = s.init == "global";
  filter::ImplicitProposal implicit_proposal;
  implicit_proposal.map = s.map;

  const auto runs = static_cast<std::size_t>(s.runs);
  const std::string settings = fmt::format(
      "global seed={} method={} M={} init={} span={:a} duration={:a} kidnap_at={:a} skip={:a} "
      "recovery={} slow={:a} fast={:a} eps={:a} kld={} err={:a} z={:a} min={} max={} "
      "cover={:a}/{} map={} clutter={} data={} config={} p={:a} q={:a} control_sd={:a} "
      "state_sd={:a} sigma2={} range_sd={:a} bearing_sd={:a} label_gate={:a}",
      ctx.seed, s.method, s.particles, s.init, s.start_span, s.duration, s.kidnap_at, s.kidnap_skip,
      s.recovery, s.recovery_alpha_slow, s.recovery_alpha_fast, s.kidnap_probability, s.kld,
      s.kld_err, s.kld_z, s.min_particles, s.max_particles, s.cover_spacing, s.cover_headings,
      name_of(s.map), s.clutter, s.data_dir, name_of(s.config), s.p, s.q,
      fmt::join(s.control_sd, ","), fmt::join(s.state_sd, ","), name_of(s.sigma2), s.range_sd,
      s.bearing_sd_deg, s.label_gate);
  ProgressBar bar(fmt::format("mcl {} {} M={}", s.init == "global" ? "global" : "kidnap", s.method,
                              s.particles),
                  runs, ctx.show_progress(), ctx.progress);
  // Run r: its seed and start depend only on r, so any rank (or the CSV writer) can redo it.
  const auto run_number = [&](std::size_t r) {
    filter::FilterOptions o = options;
    o.seed = ctx.seed * static_cast<std::uint64_t>(runs) + static_cast<std::uint64_t>(r);
    filter::GlobalOptions gr = g;
    // Run r starts r * span / runs seconds in: start times and seeds differ together.
    if (g.global_start)
      gr.start_time = t0 + s.start_span * static_cast<double>(r) / static_cast<double>(runs);
    filter::LocalizationRun run =
        s.method == "implicit"
            ? filter::run_global_localization(problem, model, sensor, implicit_proposal, o, gr)
            : filter::run_global_localization(problem, model, sensor, filter::BootstrapProposal{},
                                              o, gr);
    // The clock starts at the nominal start (a run that waits for a usable scan pays for it).
    const double from = kidnap ? t0 + s.kidnap_at + s.kidnap_skip : std::max(gr.start_time, t0);
    return std::make_pair(std::move(run), from);
  };
  const auto records = distribute_runs(ctx, "mcl-global", settings, runs, [&](std::size_t r) {
    bar.check();  // the bar ticks per run: after a stop, no run starts
    const auto [run, from] = run_number(r);
    const filter::GlobalMetrics m = filter::global_metrics(run, problem, from);
    bar.tick();
    const auto steps = static_cast<double>(run.steps.size());
    MclGlobalRunRecord rec;
    rec.success = m.success;
    rec.time_to_converge_s = m.time_to_converge;
    rec.rmse_after_settle_m = m.rmse_after_settle;
    rec.particles_mean = m.particles_mean;
    rec.particles_peak = m.particles_peak;
    rec.injected = m.injected;
    rec.cpu_ms_per_step = 1e3 * run.cpu_seconds / steps;
    rec.start_s = from - t0;
    rec.uniform_start = run.uniform_start;
    return rec;
  });
  bar.finish();
  if (rank_index() == 0 && (!s.trajectory.empty() || !s.truth_trajectory.empty()))
    write_mcl_tum_files(s, problem, run_number(0).first);
  // Only rank 0 writes (parallel_runs.hpp); the first few runs are redone for their error traces.
  if (!ctx.out_dir.empty() && rank_index() == 0)
    write_errors(ctx.csv_path(fmt::format("mcl_{}_{}_M{}_errors.csv", kidnap ? "kidnap" : "global",
                                          s.method, s.particles)),
                 problem, t0, std::min<std::size_t>(runs, 5), run_number);
  using R = MclGlobalRunRecord;
  const std::vector<double> success = column(records, &R::success),
                            converge = column(records, &R::time_to_converge_s),
                            rmse = column(records, &R::rmse_after_settle_m),
                            pmean = column(records, &R::particles_mean),
                            ppeak = column(records, &R::particles_peak),
                            injected = column(records, &R::injected),
                            cpu = column(records, &R::cpu_ms_per_step),
                            start = column(records, &R::start_s);
  int uniform_starts = 0;
  for (const R& r : records) uniform_starts += r.uniform_start ? 1 : 0;
  nlohmann::json j;
  j["method"] = s.method;
  j["init"] = s.init;
  j["source"] = g.source == filter::GlobalSource::kMixture ? "mixture" : "uniform";
  j["recovery"] = recover;
  j["particles"] = s.particles;
  j["runs"] = s.runs;
  j["seed"] = ctx.seed;
  j["kld"] = s.kld;
  if (s.kld)
    j["kld_settings"] = {{"kld_err", s.kld_err},
                         {"kld_z", s.kld_z},
                         {"min_particles", s.min_particles},
                         {"max_particles", s.max_particles}};
  j["criteria"] =
      "success: position RMSE below 1 m from 30 s after the start (kidnapping: after "
      "the gap) to the end; converged: the error stays below 1 m for 5 s";
  const std::string prefix = kidnap ? "kidnap_recovery" : "global_success";
  j[prefix + "_rate"] = mean_of(success);
  if (!empty.empty()) {
    j["empty"] = empty;  // the test did not happen: no rate (NaN, null in the JSON)
    j[prefix + "_rate"] = std::numeric_limits<double>::quiet_NaN();
  }
  j[kidnap ? "recovery_time_s_median" : "time_to_converge_s_median"] = median_of_finite(converge);
  j[kidnap ? "recovery_time_s_runs" : "time_to_converge_s_runs"] = converge;
  j["success_runs"] = success;
  j["rmse_after_settle_m_median"] = median_of_finite(rmse);
  j["particles_mean"] = mean_of(pmean);
  j["particles_peak"] = ppeak.empty() ? 0.0 : *std::max_element(ppeak.begin(), ppeak.end());
  j["injected_mean"] = mean_of(injected);
  j["cpu_ms_per_step"] = mean_of(cpu);
  j["start_s_runs"] = start;
  // Mixture starts whose first scan had no isolated minimum, which started uniform instead.
  j["uniform_fallback_starts"] = uniform_starts;
  if (kidnap) {
    j["kidnap_at_s"] = s.kidnap_at;
    j["kidnap_skip_s"] = s.kidnap_skip;
  }
  j["steps"] = problem.schedule.steps.size();
  return j;
}

}  // namespace

nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UteModel& model, const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem) {
  return run_global(s, ctx, model, sensor, problem);
}

nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UnicycleModel& model,
                              const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem) {
  return run_global(s, ctx, model, sensor, problem);
}

nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::AnyMotionModel& model,
                              const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem) {
  return run_global(s, ctx, model, sensor, problem);
}

}  // namespace implicit::experiments
