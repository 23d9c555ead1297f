// implicit.ssm.particle_filter: a particle filter for a state-space model defined by Python
// callbacks, on the library's engine (filter::ParticleEngine), with the bootstrap, the implicit
// (spec §1.2, §1.3: Newton per particle, linear or random map, exact weights) or the user's own
// proposal, ESS-triggered resampling with any of the four schemes, and the collectors of the run.
//
// Python is called a few times per step (the implicit proposal: once per Newton iteration and
// round of backtracks, for all particles at once), never once per particle. Every random number
// comes from the library's keyed streams (core/rng.hpp) and is handed to the callbacks as standard
// normals, so a seed gives the same run for any thread count and whatever numpy's global state is.

#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "implicit/core/log_weight.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/particle_engine.hpp"
#include "user_model_callbacks.hpp"

// Everything lives in ssm (not in implicit::python's unnamed namespace): the module is a unity
// build, and its other files' helpers must not meet these.
namespace implicit::python::ssm {
namespace {

enum class Proposal { kBootstrap, kImplicit, kGuided };

struct Settings {
  std::size_t particles = 1000;
  Proposal proposal = Proposal::kBootstrap;
  ResamplingScheme scheme = ResamplingScheme::kSystematic;
  double threshold = 0.5;
  std::uint64_t seed = 1;
  int threads = 0;
  bool random_map = false;
  NewtonOptions newton;
};

/// Standard normals, row j from the stream (seed, step, j, purpose): thread-count free.
RowMatrix normals(const Settings& s, long long step, std::uint64_t purpose, Eigen::Index d) {
  RowMatrix z(static_cast<Eigen::Index>(s.particles), d);
  parallel_for(s.particles, [&](std::size_t j) {
    Rng rng({s.seed, static_cast<std::uint64_t>(step), j, purpose});
    for (Eigen::Index i = 0; i < d; ++i) z(static_cast<Eigen::Index>(j), i) = rng.normal();
  });
  return z;
}

/// One step's proposal: the new particles and their log weight increments.
struct Moved {
  RowMatrix x;
  VecX increment;
  double newton_iterations = 0.0;  ///< mean over the particles (implicit)
  int newton_failures = 0;         ///< particles without an SPD factor (weight zero)
  int map_failures = 0;            ///< random map: rays without a root (weight zero)
  int objective_calls = 0;         ///< batched evaluations of F (implicit)
};

/// The linear map X = mu + L^-T xi for every particle, then F(X) in one call and the weight
/// (implicit_log_weight, as core's linear_map(), whose per-point evaluation cannot be batched).
void linear_map_all(const Callbacks& cb, const std::vector<NewtonPoint>& points,
                    const RowMatrix& xi, const RowMatrix& xp, Moved& m) {
  const Eigen::Index n = xp.rows(), d = xp.cols();
  m.x.resize(n, d);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t j) {
    const auto r = static_cast<Eigen::Index>(j);
    const NewtonPoint& p = points[j];
    VecX offset = xi.row(r).transpose();
    if (p.factor_ok) p.factor.upper_solve_in_place(offset);
    m.x.row(r) = (p.x + (p.factor_ok ? offset : VecX::Zero(d))).transpose();
  });
  const VecX fx = cb.objective(m.x, xp);
  m.increment.resize(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const NewtonPoint& p = points[static_cast<std::size_t>(r)];
    m.increment[r] = p.factor_ok ? implicit_log_weight(static_cast<int>(d), xi.row(r).squaredNorm(),
                                                       fx[r], p.factor.log_det_L())
                                 : -std::numeric_limits<double>::infinity();
  }
}

Moved implicit_step(const Callbacks& cb, const Settings& s, const RowMatrix& xp) {
  const Eigen::Index d = cb.dim;
  // Newton starts at the noise-free move: the transition with zero normals.
  const RowMatrix start = cb.sample_transition(xp, RowMatrix::Zero(xp.rows(), d));
  PythonObjective f(cb, xp);
  const std::vector<NewtonPoint> points = lockstep_newton(f, start, s.newton);
  const RowMatrix xi = normals(s, cb.step, purpose::kReference, d);
  Moved m;
  for (const NewtonPoint& p : points) {
    m.newton_iterations += p.iterations;
    m.newton_failures += p.factor_ok ? 0 : 1;
  }
  if (s.random_map) {
    MapResult r = lockstep_random_map(f, points, xi, RandomMapOptions{});
    m.x = std::move(r.x);
    m.increment = std::move(r.log_weight);
    m.map_failures = r.failures - m.newton_failures;
  } else {
    linear_map_all(cb, points, xi, xp, m);
  }
  m.newton_iterations /= static_cast<double>(xp.rows());
  m.objective_calls = f.calls + (s.random_map ? 0 : 1);
  return m;
}

Moved propose(const Callbacks& cb, const Settings& s, const RowMatrix& xp) {
  if (s.proposal == Proposal::kImplicit) return implicit_step(cb, s, xp);
  const RowMatrix z = normals(s, cb.step, purpose::kProposal, cb.dim);
  Moved m;
  if (s.proposal == Proposal::kBootstrap) {
    m.x = cb.sample_transition(xp, z);
    m.increment = cb.observation(m.x);
    return m;
  }
  auto [x, log_q] = cb.guided(xp, z);
  m.increment = cb.transition_density(x, xp) + cb.observation(x) - log_q;
  m.x = std::move(x);
  return m;
}

/// The run's collectors, one row per step.
struct Collectors {
  RowMatrix mean, variance;
  std::vector<double> ess, log_likelihood, newton_iterations;
  std::vector<int> newton_failures, map_failures, objective_calls;
  std::vector<bool> resampled;

  Collectors(std::size_t steps, Eigen::Index d)
      : mean(static_cast<Eigen::Index>(steps), d), variance(static_cast<Eigen::Index>(steps), d) {}

  void add(std::size_t t, const filter::ParticleEngine<VecX>& engine) {
    const auto r = static_cast<Eigen::Index>(t);
    const auto w = engine.weights();
    const auto ps = engine.particles();
    VecX m = VecX::Zero(mean.cols()), v = VecX::Zero(mean.cols());
    for (std::size_t j = 0; j < ps.size(); ++j) m += w[j] * ps[j];
    for (std::size_t j = 0; j < ps.size(); ++j) v += w[j] * (ps[j] - m).cwiseAbs2();
    mean.row(r) = m.transpose();
    variance.row(r) = v.transpose();
  }
};

RowMatrix population(const filter::ParticleEngine<VecX>& engine, Eigen::Index d) {
  RowMatrix x(static_cast<Eigen::Index>(engine.size()), d);
  const auto ps = engine.particles();
  for (std::size_t j = 0; j < ps.size(); ++j) x.row(static_cast<Eigen::Index>(j)) = ps[j];
  return x;
}

py::dict run_filter(Callbacks& cb, const py::sequence& observations, const Settings& s) {
  const ThreadLimit limit(s.threads);
  const Eigen::Index d = cb.dim;
  const std::size_t steps = py::len(observations);
  filter::ParticleEngine<VecX> engine(s.particles, VecX::Zero(d));
  cb.step = 0;
  const RowMatrix x0 = cb.sample_initial(normals(s, 0, purpose::kInitial, d));
  engine.generate([&](std::size_t j) -> VecX { return x0.row(static_cast<Eigen::Index>(j)); });
  Collectors c(steps, d);
  double log_likelihood = 0.0;
  for (std::size_t t = 0; t < steps; ++t) {
    cb.step = static_cast<long long>(t) + 1;
    cb.y = observations[t];
    const RowMatrix xp = population(engine, d);
    const Moved m = propose(cb, s, xp);
    engine.move([&](std::size_t j, VecX& p) {
      const auto r = static_cast<Eigen::Index>(j);
      p = m.x.row(r).transpose();
      return m.increment[r];
    });
    const filter::Reweighting w = engine.reweight();
    require(!w.all_weights_zero,
            "step {}: every particle has weight zero (all log weight increments are -inf)",
            cb.step);
    log_likelihood += w.log_likelihood_increment;
    c.add(t, engine);
    c.ess.push_back(w.ess);
    c.log_likelihood.push_back(w.log_likelihood_increment);
    c.newton_iterations.push_back(m.newton_iterations);
    c.newton_failures.push_back(m.newton_failures);
    c.map_failures.push_back(m.map_failures);
    c.objective_calls.push_back(m.objective_calls);
    const bool resample_now = needs_resampling(w.ess, s.particles, s.threshold);
    c.resampled.push_back(resample_now);
    if (resample_now) {
      Rng rng({s.seed, static_cast<std::uint64_t>(cb.step), 0, purpose::kResampling});
      engine.resample(resample(s.scheme, engine.weights(), s.particles, rng));
    }
  }
  py::dict out;
  out["mean"] = adopt(std::move(c.mean), {static_cast<py::ssize_t>(steps), d});
  out["variance"] = adopt(std::move(c.variance), {static_cast<py::ssize_t>(steps), d});
  out["ess"] = adopt_vector(std::move(c.ess));
  out["log_likelihood_increments"] = adopt_vector(std::move(c.log_likelihood));
  out["log_likelihood"] = log_likelihood;
  out["resampled"] = py::array(py::cast(c.resampled)).attr("astype")("bool");
  out["newton_iterations"] = adopt_vector(std::move(c.newton_iterations));
  out["newton_failures"] = py::array(py::cast(c.newton_failures));
  out["map_failures"] = py::array(py::cast(c.map_failures));
  out["objective_calls"] = py::array(py::cast(c.objective_calls));
  out["particles"] = adopt(population(engine, d), {static_cast<py::ssize_t>(s.particles), d});
  out["weights"] =
      py::array_t<double>(static_cast<py::ssize_t>(s.particles), engine.weights().data());
  return out;
}

py::object callable_arg(const py::object& o, const char* name, bool required) {
  if (o.is_none() && !required) return o;
  require(PyCallable_Check(o.ptr()) != 0, "{}: expected a callable, got {}", name, type_name(o));
  return o;
}

py::dict user_model_filter(const py::dict& a) {
  Callbacks cb;
  cb.dim = int_arg(a["dim"], "dim", 1, 10000);
  Settings s;
  const std::string proposal =
      choice_arg(a["proposal"], "proposal", {"bootstrap", "implicit", "guided"});
  s.proposal = proposal == "implicit" ? Proposal::kImplicit
               : proposal == "guided" ? Proposal::kGuided
                                      : Proposal::kBootstrap;
  const bool needs_density = s.proposal != Proposal::kBootstrap;
  cb.initial = callable_arg(a["initial"], "initial", true);
  cb.transition = callable_arg(a["transition"], "transition", true);
  cb.observation_logpdf = callable_arg(a["observation_logpdf"], "observation_logpdf", true);
  cb.transition_logpdf = callable_arg(a["transition_logpdf"], "transition_logpdf", false);
  cb.gradient = callable_arg(a["gradient"], "gradient", false);
  cb.hessian = callable_arg(a["hessian"], "hessian", false);
  cb.proposal = callable_arg(a["proposal_fn"], "model.proposal", false);
  require(!needs_density || !cb.transition_logpdf.is_none(),
          "transition_logpdf: the {} proposal weighs with p(x | x'), expected a callable, got "
          "None",
          proposal);
  require(s.proposal != Proposal::kGuided || !cb.proposal.is_none(),
          "proposal: 'guided' draws from the model's proposal, expected a callable, got None");
  // A particle costs its state twice (population and resampling copy), its normals, the
  // weight and the log weight.
  s.particles = particle_count_arg(a["particles"], "particles", kMaxParticles,
                                   static_cast<double>(3 * cb.dim + 2) * sizeof(double));
  s.scheme = parse_resampling_scheme(choice_arg(
      a["resampling"], "resampling", {"multinomial", "systematic", "stratified", "residual"}));
  s.random_map = choice_arg(a["map"], "map", {"linear", "random"}) == "random";
  s.threshold = number_arg(a["threshold"], "threshold", 0.0, 1.0);
  s.seed = seed_arg(a["seed"], "seed");
  s.threads = static_cast<int>(int_arg(a["threads"], "threads", 0, 1024));
  s.newton.max_iterations =
      static_cast<int>(int_arg(a["max_newton_iterations"], "max_newton_iterations", 1, 1000));
  // The weights are exact at any centre, so the minimum is needed only roughly: a Newton
  // decrement below 1e-10 (F within 1e-10 of its minimum) ends it, as does a full step below
  // 1e-7 (the next would be far below round-off). Each backtrack is a Python call: 30 at most.
  s.newton.gradient_tolerance = 1e-9;
  s.newton.decrement_tolerance = 1e-10;
  s.newton.final_step = 1e-7;
  s.newton.max_backtracks = 30;
  const py::object obs = a["observations"];
  require(py::isinstance<py::sequence>(obs) && !py::isinstance<py::str>(obs),
          "observations: expected a sequence (one observation per step), got {}", type_name(obs));
  return run_filter(cb, obs.cast<py::sequence>(), s);
}

}  // namespace
}  // namespace implicit::python::ssm

namespace implicit::python {

void init_user_model(py::module_& m) {
  m.def("_user_model_filter", &ssm::user_model_filter, py::arg("arguments"),
        "The particle filter of implicit.ssm.particle_filter (its arguments as a dict).");
}

}  // namespace implicit::python
