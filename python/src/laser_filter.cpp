// implicit.laser.ParticleFilter (laser Monte Carlo localization stepped from Python, on the
// likelihood field or the beam model) and implicit.laser._run, the experiment of `implicit mcl
// --sensor laser` (experiments/laser_mcl.hpp) called with the same settings struct, so that its
// numbers are the tool's.

#include <Python.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <span>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "experiments/choices.hpp"
#include "experiments/laser_mcl.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/filter/monte_carlo_localization.hpp"
#include "implicit/robot/distance_field.hpp"
#include "laser.hpp"

namespace implicit::python::laser {
namespace {

using robot::Mat3;
using robot::Pose;

/// The implicit proposal on the beam model, refused as the tool refuses it (LaserMclSettings::
/// validate), in Python's names. The C++ filter would not even compile it (the beam model has no
/// negative_log_likelihood), so the refusal has to come before.
constexpr const char* kBeamNeedsBootstrap =
    "proposal: the implicit proposal needs an observation model with derivatives, and the beam "
    "model has none (its expected range comes from ray casting, a step function of the pose); "
    "use proposal='bootstrap', or the likelihood field for the implicit proposal";

/// The implicit proposal needs the model's gradient; say which argument takes it away.
void require_differentiable(bool implicit, const robot::LikelihoodFieldParams& p) {
  if (!implicit) return;
  require(p.interpolation != robot::Interpolation::kNearest,
          "interpolation: the implicit proposal needs the field's gradient, which 'nearest' does "
          "not have (use 'bilinear' or 'bicubic', or the bootstrap proposal)");
  require(p.aggregation == robot::BeamAggregation::kProduct,
          "aggregation: the implicit proposal needs a likelihood, which 'cubed-sum' is not (use "
          "'product', or the bootstrap proposal)");
}

/// The filter behind the Python class, whatever its proposal.
class AnyLaserFilter {
 public:
  virtual ~AnyLaserFilter() = default;
  virtual void initialize(const Pose& mean, const Mat3& cov) = 0;
  virtual void step(const Vec<3>& u) = 0;
  virtual void step(const Vec<3>& u, const robot::LaserScan& z) = 0;
  virtual std::span<const Pose> particles() const = 0;
  virtual std::span<const double> weights() const = 0;
  virtual const filter::StepSummary& last() const = 0;
};

template <typename Model, typename Proposal>
class LaserFilterOf final : public AnyLaserFilter {
 public:
  LaserFilterOf(robot::OdometryModel motion, Model model, Proposal proposal,
                filter::FilterOptions o)
      : pf_(std::move(motion), std::move(model), std::move(proposal), o) {}
  void initialize(const Pose& mean, const Mat3& cov) override { pf_.initialize(mean, cov); }
  void step(const Vec<3>& u) override { pf_.step(u); }
  void step(const Vec<3>& u, const robot::LaserScan& z) override { pf_.step(u, z, "scan"); }
  std::span<const Pose> particles() const override { return pf_.particles(); }
  std::span<const double> weights() const override { return pf_.weights(); }
  const filter::StepSummary& last() const override { return pf_.last(); }

 private:
  filter::MonteCarloLocalization<robot::OdometryModel, Model, Proposal> pf_;
};

struct PyLaserFilter {
  std::unique_ptr<AnyLaserFilter> f;
  bool initialized = false;
};

bool same_grid(const robot::OccupancyGrid& a, const robot::OccupancyGrid& b) {
  return a.width() == b.width() && a.height() == b.height() && a.resolution() == b.resolution() &&
         a.origin() == b.origin() && std::ranges::equal(a.data(), b.data());
}

/// The filter on a BeamModel: the bootstrap proposal only, and the model's own parameters.
PyLaserFilter beam_filter(const robot::OccupancyGrid& g, const robot::BeamModel& beam,
                          bool implicit, const robot::OdometryModel& motion,
                          const filter::FilterOptions& o, const py::kwargs& kw) {
  require(!implicit, kBeamNeedsBootstrap);
  for (const auto& item : kw)
    throw InvalidArgument(fmt::format(
        "laser: '{}' is a LikelihoodField keyword, and laser is a BeamModel (give the beam "
        "model's parameters when building it)",
        printable(std::string(py::str(item.first)))));
  require(same_grid(g, beam.map()),
          "laser: expected a BeamModel built on grid, got one on another map ({} x {} cells of "
          "{} m; grid: {} x {} of {} m, or other cells)",
          beam.map().width(), beam.map().height(), beam.map().resolution(), g.width(), g.height(),
          g.resolution());
  PyLaserFilter p;
  p.f = std::make_unique<LaserFilterOf<robot::BeamModel, filter::BootstrapProposal>>(
      motion, beam, filter::BootstrapProposal{}, o);
  return p;
}

PyLaserFilter make_filter(const py::object& grid, const py::object& proposal,
                          const py::object& particles, const py::object& seed,
                          const py::object& alphas, const py::object& laser,
                          const py::object& resample_threshold, const py::object& starts,
                          const py::object& start_probe, const py::kwargs& kw) {
  const robot::OccupancyGrid& g = grid_arg(grid, "grid");
  const bool implicit = choice_arg(proposal, "proposal", {"implicit", "bootstrap"}) == "implicit";
  filter::FilterOptions o;
  o.particles = static_cast<std::size_t>(
      particle_count_arg(particles, "particles", kMaxParticles, kPoseParticleBytes));
  o.seed = seed_arg(seed, "seed");
  o.resample_threshold = number_arg(resample_threshold, "resample_threshold", 0.0, 1.0);
  const robot::OdometryModel motion(alphas_arg(alphas, "alphas"));
  if (py::isinstance<robot::BeamModel>(laser))
    return beam_filter(g, laser.cast<const robot::BeamModel&>(), implicit, motion, o, kw);
  // The field's keywords come in the dict `laser`, as keywords of the call, or both.
  py::dict merged;
  if (!laser.is_none()) {
    require(py::isinstance<py::dict>(laser),
            "laser: expected a dict of LikelihoodField keywords ({}), a BeamModel or None, got {}",
            kLaserKeywords, type_name(laser));
    merged = py::dict(laser);
  }
  for (const auto& item : kw) {
    require(!merged.contains(item.first), "laser: '{}' is given both in laser and as a keyword",
            std::string(py::str(item.first)));
    merged[item.first] = item.second;
  }
  const LaserSpec spec = laser_spec(merged, "ParticleFilter");
  require_differentiable(implicit, spec.params);
  auto field =
      std::make_shared<const robot::DistanceField>(g, spec.params.laser_likelihood_max_dist);
  robot::LikelihoodFieldModel model(field, spec.params, spec.mount);
  filter::ImplicitProposal newton;
  newton.starts = static_cast<int>(int_arg(starts, "starts", 1, 64));
  newton.start_probe = static_cast<int>(int_arg(start_probe, "start_probe", 0, 20));
  PyLaserFilter p;
  using Field = robot::LikelihoodFieldModel;
  if (implicit)
    p.f =
        std::make_unique<LaserFilterOf<Field, filter::ImplicitProposal>>(motion, model, newton, o);
  else
    p.f = std::make_unique<LaserFilterOf<Field, filter::BootstrapProposal>>(
        motion, model, filter::BootstrapProposal{}, o);
  return p;
}

py::dict summary(const filter::StepSummary& s) {
  py::dict d;
  d["step"] = s.step;
  d["mean"] = py::array_t<double>(3, s.mean.data());
  d["covariance"] = py::array_t<double>({3, 3}, s.covariance.data());  // symmetric
  d["ess"] = s.ess;
  d["resampled"] = s.resampled;
  d["updated"] = s.updated;
  d["log_likelihood_increment"] = s.log_likelihood_increment;
  d["particles"] = s.particles;
  d["beams"] = s.detections_used;
  d["newton_evaluations"] = s.newton_evaluations;
  d["fallbacks"] = s.fallbacks;
  d["failures"] = s.failures;
  return d;
}

Mat3 covariance_arg(const py::handle& o, const std::string& name) {
  const Array c = require_shape(o, name, {3, 3});
  Mat3 m;
  double largest = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      m(i, j) = c.at(i, j);
      largest = std::max(largest, std::abs(m(i, j)));
    }
  // Symmetric up to the rounding of a covariance computed in floating point.
  require((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * largest,
          "{}: expected a symmetric matrix, got one with entries (0, 1) = {} and (1, 0) = {}", name,
          m(0, 1), m(1, 0));
  require(Eigen::LLT<Mat3>(m).info() == Eigen::Success,
          "{}: expected a positive definite matrix, got diagonal ({}, {}, {})", name, m(0, 0),
          m(1, 1), m(2, 2));
  return m;
}

constexpr const char* kFilterDoc = R"doc(
Monte Carlo localization with a laser on an occupancy grid, stepped from Python: the odometry
motion model and the likelihood field, with the implicit or the bootstrap proposal, or the beam
model with the bootstrap proposal.

ParticleFilter(grid, proposal="implicit", particles=100, seed=0, alphas=(0.2, 0.2, 0.2, 0.2),
               laser=None, resample_threshold=0.5, starts=2, start_probe=0,
               **laser_keywords)

Args:
    grid: implicit.laser.OccupancyGrid, the map.
    proposal: "implicit" (implicit sampling per particle) or "bootstrap" (the motion model).
    particles: M.
    seed: particle j at step n draws from the stream (seed, n, j): the same for any thread count.
    alphas: alpha1..alpha4 of the odometry model.
    laser: a dict of LikelihoodField keywords (z_hit, z_rand, sigma_hit, max_dist, max_beams,
        interpolation, aggregation, mount); they may also be given as keywords of the call. Or
        an implicit.laser.BeamModel built on grid: the filter weights by the beam model (with
        proposal="bootstrap": the implicit proposal needs derivatives the beam model has not).
    resample_threshold: resample when ESS < threshold * M.
    starts: the implicit proposal's Newton starts per particle: the prediction and starts - 1
        draws from the motion prior; the lowest minimum centres the proposal (weights stay
        exact). Not used by the bootstrap proposal.
    start_probe: Newton iterations a further start runs before it must be below the best
        minimum found, else it is dropped (0: every start runs to convergence; the weights stay
        exact either way).

initialize(mean (3,), covariance (3, 3)) draws the particles; step(u, ranges=None, angle_min=None,
angle_increment=None, range_min=0.0, range_max=None) moves them by the odometry increment u (3,)
(dx, dy, dtheta in the previous odometry frame) and, when ranges is given, weights them by the
scan seen after the move. step returns a dict: step, mean (3,), covariance (3, 3), ess, resampled,
updated, log_likelihood_increment, particles (the count M), beams used, newton_evaluations (mean
per particle), fallbacks, failures. particles (M, 3) and weights (M,) are copies; last is the
dict of the last step.

Example::

    pf = implicit.laser.ParticleFilter(grid, particles=200, seed=1, sigma_hit=0.1)
    pf.initialize([1.0, 1.0, 0.0], np.diag([0.01, 0.01, 0.003]))
    r = pf.step([0.2, 0.0, 0.0], **implicit.laser.simulate_scan(grid, [1.2, 1.0, 0.0]))
    beam = implicit.laser.ParticleFilter(grid, proposal="bootstrap",
                                         laser=implicit.laser.BeamModel(grid, sigma_hit=0.1)))doc";

void bind_filter(py::module_& m) {
  py::class_<PyLaserFilter>(m, "ParticleFilter", kFilterDoc)
      .def(py::init(&make_filter), py::arg("grid"), py::arg("proposal") = "implicit",
           py::arg("particles") = 100, py::arg("seed") = 0,
           py::arg("alphas") = py::make_tuple(0.2, 0.2, 0.2, 0.2), py::arg("laser") = py::none(),
           py::arg("resample_threshold") = 0.5, py::arg("starts") = 2, py::arg("start_probe") = 0)
      .def(
          "initialize",
          [](PyLaserFilter& p, const py::object& mean, const py::object& covariance) {
            const Pose x = vec3_arg(mean, "mean");
            const Mat3 c = covariance_arg(covariance, "covariance");
            p.f->initialize(x, c);
            p.initialized = true;
          },
          py::arg("mean"), py::arg("covariance"),
          "Draws the particles from N(mean (3,), covariance (3, 3)) with equal weights.")
      .def(
          "step",
          [](PyLaserFilter& p, const py::object& u, const py::object& ranges,
             const py::object& angle_min, const py::object& angle_increment,
             const py::object& range_min, const py::object& range_max) {
            require(p.initialized, "step: call initialize(mean, covariance) first");
            const Vec<3> du = vec3_arg(u, "u");
            if (ranges.is_none()) {
              require(angle_min.is_none() && angle_increment.is_none() && range_max.is_none(),
                      "ranges: expected the scan's ranges with angle_min, angle_increment and "
                      "range_max, got None");
              py::gil_scoped_release unlocked;
              p.f->step(du);
            } else {
              const robot::LaserScan z =
                  scan_arg(ranges, angle_min, angle_increment, range_min, range_max);
              py::gil_scoped_release unlocked;
              p.f->step(du, z);
            }
            return summary(p.f->last());
          },
          py::arg("u"), py::arg("ranges") = py::none(), py::arg("angle_min") = py::none(),
          py::arg("angle_increment") = py::none(), py::arg("range_min") = 0.0,
          py::arg("range_max") = py::none(),
          "Moves the particles by the odometry increment u (3,), then weights them by the scan "
          "(ranges [m], +inf no return, at bearings angle_min + i angle_increment [rad]) when "
          "ranges is given. Returns the step's summary dict.")
      .def_property_readonly(
          "particles",
          [](const PyLaserFilter& p) {
            const std::span<const Pose> s = p.f->particles();
            py::array_t<double> a({static_cast<py::ssize_t>(s.size()), py::ssize_t{3}});
            for (std::size_t j = 0; j < s.size(); ++j)
              for (int i = 0; i < 3; ++i) a.mutable_at(j, i) = s[j](i);
            return a;
          },
          "The particles (M, 3), a copy.")
      .def_property_readonly(
          "weights",
          [](const PyLaserFilter& p) {
            const std::span<const double> w = p.f->weights();
            return py::array_t<double>(static_cast<py::ssize_t>(w.size()), w.data());
          },
          "The normalised weights (M,), a copy.")
      .def_property_readonly(
          "last", [](const PyLaserFilter& p) { return summary(p.f->last()); },
          "The summary dict of the last step (of initialize before any step).");
}

/// The settings dict implicit.laser.run passes: every key is present.
struct RunArgs {
  const py::dict& kw;
  py::object operator()(const char* key) const {
    require(kw.contains(key), "run: missing setting '{}'", key);
    return kw[key];
  }
};

/// The observation model of a run, mapped as the tool maps its flags (cmd_mcl_laser.cpp): the
/// shared parameters (nav2's names) mean the same in both models.
void read_laser_model(const RunArgs& arg, bool implicit, experiments::LaserMclSettings& s) {
  py::dict field;
  for (const char* key :
       {"z_hit", "z_rand", "sigma_hit", "max_dist", "max_beams", "interpolation", "aggregation"})
    field[key] = arg(key);
  s.laser = laser_spec(field, "run").params;
  if (!arg("laser_max_range").is_none())
    s.laser.laser_max_range =
        number_arg(arg("laser_max_range"), "laser_max_range", 0.0, kInf, true);
  py::dict beam;
  for (const char* key : {"z_short", "z_max", "lambda_short"}) beam[key] = arg(key);
  s.beam = beam_spec(beam, "run").params;
  s.beam.z_hit = s.laser.z_hit;
  s.beam.z_rand = s.laser.z_rand;
  s.beam.sigma_hit = s.laser.sigma_hit;
  s.beam.max_beams = s.laser.max_beams;
  s.beam.laser_max_range = s.laser.laser_max_range;
  s.laser_model = experiments::parse_laser_model(
      choice_arg(arg("laser_model"), "laser_model", experiments::laser_models().names()));
  if (s.laser_model == experiments::LaserModelKind::kBeam)
    require(!implicit, kBeamNeedsBootstrap);
  else
    require_differentiable(implicit, s.laser);
}

/// KLD-sampling and recovery, as the tool maps --kld and --recovery: the particle count adapts
/// between min(100, M) and max(5000, M); recovery is "uniform" or "none" (the tool's "auto" is
/// none for laser runs).
void read_kld_recovery(const RunArgs& arg, experiments::LaserMclSettings& s) {
  s.kld.enabled = bool_arg(arg("kld"), "kld");
  s.kld.kld_err = number_arg(arg("kld_err"), "kld_err", 1e-6, 1.0);  // --kld-err's range
  s.kld.kld_z = number_arg(arg("kld_z"), "kld_z", 0.0, 10.0);
  const py::object recovery = arg("recovery");
  require(!(py::isinstance<py::str>(recovery) && recovery.cast<std::string>() == "mixture"),
          "recovery: 'mixture' is the landmark runs' source (over the minima of -log p(z | x)); "
          "a laser run takes 'uniform' (AMCL's, over the free cells) or 'none'");
  s.recovery.enabled = choice_arg(recovery, "recovery", {"none", "uniform"}) == "uniform";
  const double slow = number_arg(arg("recovery_alpha_slow"), "recovery_alpha_slow", 0.0, 1.0, true);
  const double fast = number_arg(arg("recovery_alpha_fast"), "recovery_alpha_fast", 0.0, 1.0, true);
  require(fast > slow, "recovery_alpha_fast: expected a number > recovery_alpha_slow = {}, got {}",
          slow, fast);
  s.recovery.recovery_alpha_slow = slow;
  s.recovery.recovery_alpha_fast = fast;
  s.recovery.kidnap_probability =
      number_arg(arg("kidnap_probability"), "kidnap_probability", 0.0, 0.5, true);
}

std::string run(const py::dict& kw, const py::object& progress) {
  const RunArgs arg{kw};
  experiments::LaserMclSettings s;
  s.data.data = path_arg(arg("data"), "data");
  if (!arg("map").is_none()) s.data.map = path_arg(arg("map"), "map");
  s.data.map_resolution = number_arg(arg("map_resolution"), "map_resolution", 0.005, 1.0);
  s.data.map_min_echoes =
      static_cast<int>(int_arg(arg("map_min_echoes"), "map_min_echoes", 0, 255));
  s.data.update_min_d = number_arg(arg("update_min_d"), "update_min_d", 0.0, kInf);
  s.data.update_min_a = number_arg(arg("update_min_a"), "update_min_a", 0.0, kInf);
  s.data.max_updates =
      static_cast<std::size_t>(int_arg(arg("max_updates"), "max_updates", 0, kMaxInt));
  const bool implicit =
      choice_arg(arg("proposal"), "proposal", {"implicit", "bootstrap"}) == "implicit";
  s.proposal =
      implicit ? experiments::ProposalKind::kImplicit : experiments::ProposalKind::kBootstrap;
  s.implicit_map = choice_arg(arg("implicit_map"), "implicit_map", {"linear", "random"}) == "linear"
                       ? filter::ImplicitMap::kLinear
                       : filter::ImplicitMap::kRandom;
  s.implicit_starts = static_cast<int>(int_arg(arg("starts"), "starts", 1, 64));
  s.implicit_start_probe = static_cast<int>(int_arg(arg("start_probe"), "start_probe", 0, 20));
  s.particles = static_cast<std::size_t>(
      particle_count_arg(arg("particles"), "particles", kMaxParticles, kPoseParticleBytes));
  s.runs = static_cast<int>(int_arg(arg("runs"), "runs", 1, 100000));
  s.seed = seed_arg(arg("seed"), "seed");
  // None keeps the experiment's defaults, so that a run without them is the tool's without them.
  if (!arg("alphas").is_none()) s.odometry_noise = alphas_arg(arg("alphas"), "alphas");
  s.filter_alphas = arg("filter_alphas").is_none()
                        ? s.odometry_noise
                        : alphas_arg(arg("filter_alphas"), "filter_alphas");
  read_laser_model(arg, implicit, s);
  s.start = choice_arg(arg("start"), "start", {"known", "global"}) == "known"
                ? experiments::StartKind::kKnown
                : experiments::StartKind::kGlobal;
  s.global_updates = static_cast<int>(int_arg(arg("global_updates"), "global_updates", 1, 100000));
  s.global_success_radius = number_arg(arg("global_radius"), "global_radius", 0.0, kInf, true);
  read_kld_recovery(arg, s);
  s.keep_tracks = bool_arg(arg("tracks"), "tracks");
  const int threads = static_cast<int>(int_arg(arg("threads"), "threads", 0, 100000));
  require(progress.is_none() || PyCallable_Check(progress.ptr()),
          "progress: expected a callable progress(done, total) or None, got {}",
          type_name(progress));
  // Called between runs, with the interpreter's lock: the user's callback, and Ctrl-C.
  const experiments::Progress report = [&](int done, int total) {
    py::gil_scoped_acquire locked;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!progress.is_none()) progress(done, total);
  };
  nlohmann::json j;
  {
    py::gil_scoped_release unlocked;
    ThreadLimit limit(threads);
    j = experiments::to_json(experiments::run_laser_mcl(s, report), s.keep_tracks);
  }
  return j.dump();
}

}  // namespace

void init_laser_filter(py::module_& m) {
  bind_filter(m);
  m.def("_run", &run, py::arg("settings"), py::arg("progress") = py::none(),
        "The experiment of `implicit mcl --sensor laser --json` (use implicit.laser.run).");
}

}  // namespace implicit::python::laser
