// Runs of laser MCL on a prepared dataset (laser_mcl.hpp): tracking from a known start, and
// global starts, with either proposal.
#include "experiments/laser_mcl.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <type_traits>

#include "experiments/laser_global.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/monte_carlo_localization.hpp"
#include "implicit/filter/pose_clusters.hpp"
#include "implicit/robot/distance_field.hpp"

namespace implicit::experiments {

std::string_view to_string(LaserModelKind m) {
  return m == LaserModelKind::kBeam ? "beam" : "likelihood-field";
}

LaserModelKind parse_laser_model(std::string_view text) {
  if (text == "likelihood-field") return LaserModelKind::kLikelihoodField;
  if (text == "beam") return LaserModelKind::kBeam;
  throw InvalidArgument(fmt::format("expected a laser model 'likelihood-field' or 'beam', got '{}'",
                                    printable(text)));
}

std::string_view to_string(EstimateKind e) {
  return e == EstimateKind::kHeaviestCluster ? "cluster" : "mean";
}

EstimateKind parse_estimate(std::string_view text) {
  if (text == "mean") return EstimateKind::kMean;
  if (text == "cluster") return EstimateKind::kHeaviestCluster;
  throw InvalidArgument(
      fmt::format("expected an estimate 'mean' or 'cluster', got '{}'", printable(text)));
}

void LaserMclSettings::validate() const {
  require(particles >= 1 && particles <= 10'000'000,
          "laser MCL: expected 1 to 10000000 particles, got {}", particles);
  require(runs >= 1 && runs <= 100000, "laser MCL: expected 1 to 100000 runs, got {}", runs);
  require(implicit_starts >= 1 && implicit_starts <= 64,
          "laser MCL: expected 1 to 64 Newton starts per particle, got {}", implicit_starts);
  require(implicit_start_probe >= 0 && implicit_start_probe <= 20,
          "laser MCL: expected a start probe of 0 (off) to 20 Newton iterations, got {}",
          implicit_start_probe);
  require(implicit_defensive >= 0 && implicit_defensive < 1,
          "laser MCL: expected a defensive share in [0, 1), got {}", implicit_defensive);
  require(implicit_defensive == 0 || implicit_map == filter::ImplicitMap::kLinear,
          "laser MCL: the defensive share needs the linear map (the random map's density is not "
          "known in closed form), got a share of {} with the random map",
          implicit_defensive);
  odometry_noise.validate();
  filter_alphas.validate();
  laser.validate();
  beam.validate();
  require(!(laser_model == LaserModelKind::kBeam && proposal == ProposalKind::kImplicit),
          "laser MCL: the implicit proposal needs an observation model with derivatives, and the "
          "beam model has none (its expected range comes from ray casting, a step function of "
          "the pose); use the likelihood field (--laser-model likelihood-field) or the bootstrap "
          "proposal");
  if (kld.enabled) filter::validate(kld);
  if (recovery.enabled) filter::validate(recovery);
  require(resample_threshold >= 0 && resample_threshold <= 1,
          "laser MCL: expected a resampling threshold in [0, 1], got {}", resample_threshold);
  require(initial_std_xy > 0 && std::isfinite(initial_std_xy) && initial_std_heading > 0 &&
              std::isfinite(initial_std_heading),
          "laser MCL: expected a positive initial spread, got {} m and {} rad", initial_std_xy,
          initial_std_heading);
  require(lost_threshold > 0 && std::isfinite(lost_threshold),
          "laser MCL: expected a positive lost threshold, got {} m", lost_threshold);
  require(global_success_radius > 0 && std::isfinite(global_success_radius),
          "laser MCL: expected a positive global success radius, got {} m", global_success_radius);
  require(global_updates >= 1, "laser MCL: expected global_updates >= 1, got {}", global_updates);
}

namespace {

using Motion = robot::OdometryModel;

double seconds_of_cpu() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

struct Track {
  std::vector<robot::Pose> estimates;
  std::vector<double> ess_fraction, particles, newton;
  int fallbacks = 0, failures = 0;
  double cpu_seconds = 0.0;
  std::size_t updates = 0;
  double first_fit_reference = std::numeric_limits<double>::quiet_NaN();
  double first_fit_best = std::numeric_limits<double>::quiet_NaN();
};

/// Runs one filter over updates [first, last] (the filter starts at update `first`, already
/// initialised there) and records the estimate at each update.
template <typename Filter>
robot::Pose estimate_of(const Filter& pf, EstimateKind kind) {
  if (kind == EstimateKind::kMean) return pf.last().mean;
  return filter::heaviest_cluster(pf.particles(), pf.weights()).mean;
}

template <typename Filter>
void follow(Filter& pf, const LaserDataset& d, const std::vector<Vec<3>>& odometry,
            std::size_t first, std::size_t last, EstimateKind estimate, Track& t) {
  for (std::size_t k = first + 1; k <= last; ++k) {
    const double c0 = seconds_of_cpu();
    const filter::StepSummary& s =
        pf.step(odometry[k], d.scans[k], "laser update " + std::to_string(k));
    t.cpu_seconds += seconds_of_cpu() - c0;
    ++t.updates;
    t.estimates.push_back(estimate == EstimateKind::kMean ? s.mean : estimate_of(pf, estimate));
    t.ess_fraction.push_back(s.ess / static_cast<double>(s.particles));
    t.particles.push_back(static_cast<double>(s.particles));
    t.newton.push_back(s.newton_evaluations);
    t.fallbacks += s.fallbacks;
    t.failures += s.failures;
  }
}

/// The start of a global run: uniform over free space (the bootstrap proposal, or a model without
/// derivatives), or the likelihood field's multi-start mixture (implicit).
template <typename Model>
GlobalStart start_anywhere(const LaserMclSettings& s, const LaserDataset& d, const Model& model,
                           const FreeSpace& space, std::size_t first, std::uint64_t seed) {
  if constexpr (std::is_same_v<Model, robot::LikelihoodFieldModel>) {
    return global_start(model, d.map, d.scans[first], s.particles,
                        s.proposal == ProposalKind::kImplicit, seed);
  } else {
    return uniform_global_start(
        model, space, model.prepare(d.scans[first], "the global start's scan"), s.particles, seed);
  }
}

/// log p(z | x) at the scan-matched pose nearest `reference` (match_scan_near, for a
/// differentiable model; else at `reference`).
template <typename Model>
double fit_near(const Model& model, const typename Model::Prepared& z,
                const robot::Pose& reference) {
  if constexpr (std::is_same_v<Model, robot::LikelihoodFieldModel>) {
    if (model.differentiable()) {
      const auto r = match_scan_near(model, z, reference);
      if (r.x.allFinite())
        return std::max(model.log_likelihood(z, r.x), model.log_likelihood(z, reference));
    }
  }
  return model.log_likelihood(z, reference);
}

/// The first scan's fit at the reference and at the start's best particle (LaserMclRun).
template <typename Model>
void score_first_scan(const Model& model, const LaserDataset& d, std::size_t first,
                      const GlobalStart& g, Track& t) {
  if (!d.reference[first].allFinite()) return;
  const auto z = model.prepare(d.scans[first], "the global start's scan");
  t.first_fit_reference = fit_near(model, z, d.reference[first]);
  double best = -std::numeric_limits<double>::infinity();
  for (const robot::Pose& x : g.particles) best = std::max(best, model.log_likelihood(z, x));
  t.first_fit_best = best;
}

template <typename Model, typename Proposal>
Track run_one(const LaserMclSettings& s, const LaserDataset& d, const Model& model,
              const std::shared_ptr<const FreeSpace>& space, Proposal proposal, std::uint64_t seed,
              std::size_t first, std::size_t last) {
  const std::vector<Vec<3>> odometry = run_odometry(d, s.odometry_noise, seed);
  filter::FilterOptions o;
  o.particles = s.particles;
  o.seed = seed;
  o.resample_threshold = s.resample_threshold;
  o.kld = s.kld;
  o.kld.min_particles = std::min(o.kld.min_particles, s.particles);
  o.kld.max_particles = std::max(o.kld.max_particles, s.particles);
  o.recovery = s.recovery;
  filter::MonteCarloLocalization pf(Motion(s.filter_alphas), model, proposal, o);
  using Filter = decltype(pf);
  if (s.recovery.enabled)
    pf.set_recovery_source(std::make_shared<UniformRecovery<typename Filter::Context>>(space));
  Track t;
  if (s.start == StartKind::kKnown) {
    const Vec<3> sd(s.initial_std_xy, s.initial_std_xy, s.initial_std_heading);
    // The start is drawn around the reference: its offset is part of the run's randomness.
    Rng rng({seed, 0, 1, purpose::kInitial});
    const Vec<3> xi = rng.normal_vector<3>();
    const robot::Pose start = d.reference[first] + (sd.array() * xi.array()).matrix();
    pf.initialize(start, Mat<3>(sd.array().square().matrix().asDiagonal()));
    t.estimates.push_back(start);
  } else {
    const GlobalStart g = start_anywhere(s, d, model, *space, first, seed);
    pf.initialize(g.particles, g.log_weights);
    score_first_scan(model, d, first, g, t);
    t.estimates.push_back(estimate_of(pf, s.estimate));
  }
  t.ess_fraction.push_back(1.0);
  follow(pf, d, odometry, first, last, s.estimate, t);
  return t;
}

/// The run's scores from its track against the reference of updates [first, ...].
LaserMclRun score(const LaserMclSettings& s, const LaserDataset& d, const Track& t,
                  std::uint64_t seed, std::size_t first) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  LaserMclRun r;
  r.seed = seed;
  r.final_error_m = nan;
  double sum_p = 0.0, sum_h = 0.0;
  int headed = 0, converged_from = -1;
  for (std::size_t i = 0; i < t.estimates.size(); ++i) {
    const robot::Pose& ref = d.reference[first + i];
    // A robot log's update without truth (NaN) is not scored; one without heading scores the
    // position only.
    const double e = (t.estimates[i].head<2>() - ref.head<2>()).norm();
    if (s.keep_tracks) r.errors_m.push_back(e);
    if (std::isnan(e)) continue;
    const double h = std::abs(wrap_angle(t.estimates[i](2) - ref(2)));
    ++r.scored_updates;
    sum_p += e * e;
    r.final_error_m = e;
    if (!std::isnan(h)) {
      ++headed;
      sum_h += h * h;
    }
    const bool good = e < s.global_success_radius && !(h >= 0.3);
    if (!good)
      converged_from = -1;
    else if (converged_from < 0)
      converged_from = static_cast<int>(i);
  }
  r.position_rmse_m =
      r.scored_updates > 0 ? std::sqrt(sum_p / static_cast<double>(r.scored_updates)) : nan;
  r.heading_rmse_rad = headed > 0 ? std::sqrt(sum_h / static_cast<double>(headed)) : nan;
  r.lost = r.final_error_m > s.lost_threshold;
  r.updates_to_converge = converged_from;
  r.global_success = converged_from >= 0 && converged_from <= s.global_updates;
  auto mean = [](const std::vector<double>& v) {
    return v.empty() ? 0.0
                     : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  };
  r.ess_fraction_mean = mean(t.ess_fraction);
  r.particles_mean = mean(t.particles);
  r.newton_evaluations_mean = mean(t.newton);
  r.cpu_us_per_update = t.updates ? 1e6 * t.cpu_seconds / static_cast<double>(t.updates) : 0.0;
  r.fallbacks = t.fallbacks;
  r.failures = t.failures;
  r.first_scan_fit_reference = t.first_fit_reference;
  r.first_scan_fit_best = t.first_fit_best;
  if (s.keep_tracks) r.estimates = t.estimates;
  return r;
}

MeanSe mean_se(const std::vector<LaserMclRun>& runs, double LaserMclRun::*field) {
  std::vector<double> v;
  for (const LaserMclRun& r : runs) v.push_back(r.*field);
  MeanSe m;
  // A run that scored nothing (no truth) leaves the summary undefined, not a mean of the rest.
  if (std::any_of(v.begin(), v.end(), [](double x) { return std::isnan(x); }))
    return {std::nan(""), std::nan(""), std::nan("")};
  const double n = static_cast<double>(v.size());
  m.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double q = 0.0;
  for (double x : v) q += (x - m.mean) * (x - m.mean);
  m.se = v.size() > 1 ? std::sqrt(q / (n - 1.0) / n) : 0.0;
  std::sort(v.begin(), v.end());
  m.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  return m;
}

}  // namespace

LaserMclResult run_laser_mcl(const LaserMclSettings& settings, const LaserDataset& d,
                             const Progress& progress) {
  settings.validate();
  require(d.scans.size() >= 2 && d.scans.size() == d.reference.size(),
          "laser MCL: expected a dataset with at least 2 updates");
  require(settings.start == StartKind::kGlobal || d.reference.front().allFinite(),
          "laser MCL on {}: a known start begins at the reference pose of the first update, and "
          "the log has no truth (with heading) at its time {} s; add truth records, or start "
          "anywhere (--init global)",
          d.name, d.scans.front().time);
  const auto wall0 = std::chrono::steady_clock::now();
  const auto space = std::make_shared<const FreeSpace>(d.map);
  // One filter run of the chosen observation model and proposal.
  std::function<Track(std::uint64_t, std::size_t, std::size_t)> run_filter;
  if (settings.laser_model == LaserModelKind::kBeam) {
    const robot::BeamModel beam(std::make_shared<const robot::OccupancyGrid>(d.map), settings.beam,
                                d.mount);
    run_filter = [&settings, &d, space, beam](std::uint64_t seed, std::size_t first,
                                              std::size_t last) {
      return run_one(settings, d, beam, space, filter::BootstrapProposal{}, seed, first, last);
    };
  } else {
    auto field = std::make_shared<const robot::DistanceField>(
        d.map, settings.laser.laser_likelihood_max_dist);
    const robot::LikelihoodFieldModel model(field, settings.laser, d.mount);
    run_filter = [&settings, &d, space, model](std::uint64_t seed, std::size_t first,
                                               std::size_t last) {
      if (settings.proposal == ProposalKind::kBootstrap)
        return run_one(settings, d, model, space, filter::BootstrapProposal{}, seed, first, last);
      filter::ImplicitProposal p;
      p.map = settings.implicit_map;
      p.starts = settings.implicit_starts;
      p.start_probe = settings.implicit_start_probe;
      p.defensive = settings.implicit_defensive;
      return run_one(settings, d, model, space, p, seed, first, last);
    };
  }
  LaserMclResult result;
  result.settings = settings;
  result.data_name = d.name;
  result.scans_in_log = d.scans_in_log;
  result.updates = d.scans.size();
  result.map_width = d.map.width();
  result.map_height = d.map.height();
  result.map_resolution = d.map.resolution();
  result.map_built = d.map_built;
  result.odometry_recorded = d.odometry_recorded();
  const std::size_t n = d.scans.size();
  for (int run = 0; run < settings.runs; ++run) {
    const std::uint64_t seed = settings.seed + static_cast<std::uint64_t>(run);
    // Tracking runs cover the whole log; global runs start spread over it (run r at update
    // r n / runs) and last global_updates updates past the first.
    std::size_t first = 0, last = n - 1;
    if (settings.start == StartKind::kGlobal) {
      const auto span = static_cast<std::size_t>(settings.global_updates);
      require(n > span, "laser MCL: a global start needs more than {} updates, the log has {}",
              span, n);
      first = static_cast<std::size_t>(run) * (n - span) / static_cast<std::size_t>(settings.runs);
      last = first + span;
    }
    const Track t = run_filter(seed, first, last);
    result.runs.push_back(score(settings, d, t, seed, first));
    if (progress) progress(run + 1, settings.runs);
  }
  result.position_rmse_m = mean_se(result.runs, &LaserMclRun::position_rmse_m);
  result.heading_rmse_rad = mean_se(result.runs, &LaserMclRun::heading_rmse_rad);
  result.cpu_us_per_update = mean_se(result.runs, &LaserMclRun::cpu_us_per_update);
  result.ess_fraction = mean_se(result.runs, &LaserMclRun::ess_fraction_mean);
  result.particles = mean_se(result.runs, &LaserMclRun::particles_mean);
  for (const LaserMclRun& r : result.runs) {
    result.lost_runs += r.lost ? 1 : 0;
    result.scored_updates += static_cast<std::size_t>(r.scored_updates);
    result.global_success_rate += r.global_success ? 1.0 / settings.runs : 0.0;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

LaserMclResult run_laser_mcl(const LaserMclSettings& settings, const Progress& progress) {
  settings.validate();
  return run_laser_mcl(settings, load_laser_dataset(settings.data), progress);
}

namespace {
nlohmann::json to_json(const MeanSe& m) {
  return {{"mean", m.mean}, {"se", m.se}, {"median", m.median}};
}
}  // namespace

nlohmann::json to_json(const LaserMclResult& r, bool include_tracks) {
  const LaserMclSettings& s = r.settings;
  nlohmann::json j;
  j["experiment"] = "laser_mcl";
  j["data"] = r.data_name;
  j["proposal"] = to_string(s.proposal);
  j["implicit_map"] = s.implicit_map == filter::ImplicitMap::kLinear ? "linear" : "random";
  j["start"] = to_string(s.start);
  j["estimate"] = to_string(s.estimate);
  j["implicit_starts"] = s.implicit_starts;
  j["implicit_start_probe"] = s.implicit_start_probe;
  j["implicit_defensive"] = s.implicit_defensive;
  j["particles"] = s.particles;
  j["runs"] = s.runs;
  j["seed"] = s.seed;
  j["scans_in_log"] = r.scans_in_log;
  j["updates"] = r.updates;
  j["map"] = {
      {"width", r.map_width},
      {"height", r.map_height},
      {"resolution", r.map_resolution},
      {"built_from_reference", r.map_built},
      {"min_echoes", r.map_built ? nlohmann::json(s.data.map_min_echoes) : nlohmann::json()}};
  const auto alphas = [](const robot::OdometryAlphas& a) {
    return nlohmann::json{
        {"alpha1", a.alpha1}, {"alpha2", a.alpha2}, {"alpha3", a.alpha3}, {"alpha4", a.alpha4}};
  };
  j["odometry"] = r.odometry_recorded ? "recorded" : "synthesised";
  j["odometry_noise"] = r.odometry_recorded ? nlohmann::json(nullptr) : alphas(s.odometry_noise);
  j["filter_alphas"] = alphas(s.filter_alphas);
  j["laser_model"] = to_string(s.laser_model);
  if (s.laser_model == LaserModelKind::kBeam)
    j["beam"] = {{"z_hit", s.beam.z_hit},         {"z_short", s.beam.z_short},
                 {"z_max", s.beam.z_max},         {"z_rand", s.beam.z_rand},
                 {"sigma_hit", s.beam.sigma_hit}, {"lambda_short", s.beam.lambda_short},
                 {"max_beams", s.beam.max_beams}};
  j["kld"] = s.kld.enabled
                 ? nlohmann::json{{"kld_err", s.kld.kld_err},
                                  {"kld_z", s.kld.kld_z},
                                  {"min_particles", std::min(s.kld.min_particles, s.particles)},
                                  {"max_particles", std::max(s.kld.max_particles, s.particles)}}
                 : nlohmann::json(nullptr);
  j["recovery"] = s.recovery.enabled
                      ? nlohmann::json{{"source", "uniform"},
                                       {"recovery_alpha_slow", s.recovery.recovery_alpha_slow},
                                       {"recovery_alpha_fast", s.recovery.recovery_alpha_fast},
                                       {"kidnap_probability", s.recovery.kidnap_probability}}
                      : nlohmann::json(nullptr);
  if (s.laser_model == LaserModelKind::kLikelihoodField)
    j["laser"] = {{"z_hit", s.laser.z_hit},
                  {"z_rand", s.laser.z_rand},
                  {"sigma_hit", s.laser.sigma_hit},
                  {"laser_likelihood_max_dist", s.laser.laser_likelihood_max_dist},
                  {"max_beams", s.laser.max_beams},
                  {"interpolation", to_string(s.laser.interpolation)}};
  j["update_min_d"] = s.data.update_min_d;
  j["update_min_a"] = s.data.update_min_a;
  j["position_rmse_m"] = to_json(r.position_rmse_m);
  j["heading_rmse_rad"] = to_json(r.heading_rmse_rad);
  j["cpu_us_per_update"] = to_json(r.cpu_us_per_update);
  j["cpu_us_per_update_per_particle"] = r.cpu_us_per_update.mean / std::max(r.particles.mean, 1.0);
  j["ess_fraction"] = to_json(r.ess_fraction);
  j["particles_mean"] = to_json(r.particles);
  j["lost_runs"] = r.lost_runs;
  j["scored_updates"] = r.scored_updates;
  if (s.start == StartKind::kGlobal) {
    j["global_success_rate"] = r.global_success_rate;
    j["global_updates"] = s.global_updates;
    j["global_success_radius_m"] = s.global_success_radius;
  }
  j["seconds"] = r.seconds;
  nlohmann::json runs = nlohmann::json::array();
  for (const LaserMclRun& run : r.runs) {
    nlohmann::json x = {{"seed", run.seed},
                        {"position_rmse_m", run.position_rmse_m},
                        {"heading_rmse_rad", run.heading_rmse_rad},
                        {"final_error_m", run.final_error_m},
                        {"scored_updates", run.scored_updates},
                        {"lost", run.lost},
                        {"ess_fraction_mean", run.ess_fraction_mean},
                        {"particles_mean", run.particles_mean},
                        {"cpu_us_per_update", run.cpu_us_per_update},
                        {"newton_evaluations_mean", run.newton_evaluations_mean},
                        {"fallbacks", run.fallbacks},
                        {"failures", run.failures}};
    if (s.start == StartKind::kGlobal) {
      x["global_success"] = run.global_success;
      x["updates_to_converge"] = run.updates_to_converge;
      x["first_scan_fit_reference"] = run.first_scan_fit_reference;
      x["first_scan_fit_best"] = run.first_scan_fit_best;
    }
    if (include_tracks) {
      nlohmann::json est = nlohmann::json::array();
      for (const robot::Pose& p : run.estimates) est.push_back({p(0), p(1), p(2)});
      x["estimates"] = est;
      x["errors_m"] = run.errors_m;
    }
    runs.push_back(x);
  }
  j["per_run"] = runs;
  return j;
}

}  // namespace implicit::experiments
