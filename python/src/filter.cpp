// implicit.ParticleFilter (localization) and implicit.slam.Filter: filters stepped from Python.
// Each step releases the GIL and runs the C++ engine (particles in parallel); particles and
// weights are read-only numpy views of the engine's buffers.

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "common.hpp"
#include "implicit/filter/particle_filter.hpp"
#include "implicit/slam/slam_filter.hpp"
#include "robot.hpp"

namespace implicit::python {
namespace {

using filter::LabelledMeasurement;
using filter::StepSummary;
using robot::Control;
using robot::Measurement;
using robot::Pose;

/// The filter behind the Python class, whatever its motion model and proposal.
class AnyFilter {
 public:
  virtual ~AnyFilter() = default;
  virtual void initialize(const Pose& mean, const Mat<3>& cov) = 0;
  virtual void set_step_length(double dt) = 0;
  virtual const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z) = 0;
  virtual std::span<const Pose> particles() const = 0;
  virtual std::span<const double> weights() const = 0;
  virtual const StepSummary& last() const = 0;
};

template <typename Motion, typename Proposal>
class FilterOf final : public AnyFilter {
 public:
  FilterOf(Motion m, robot::RangeBearingSensor s, robot::LandmarkMap map, Proposal p,
           filter::FilterOptions o)
      : pf_(std::move(m), std::move(s), std::move(map), std::move(p), o) {}
  void initialize(const Pose& mean, const Mat<3>& cov) override { pf_.initialize(mean, cov); }
  void set_step_length(double dt) override { pf_.set_step_length(dt); }
  const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z) override {
    return pf_.step(u, z);
  }
  std::span<const Pose> particles() const override { return pf_.particles(); }
  std::span<const double> weights() const override { return pf_.weights(); }
  const StepSummary& last() const override { return pf_.last(); }

 private:
  filter::ParticleFilter<Motion, robot::RangeBearingSensor, Proposal> pf_;
};

template <typename Motion>
std::unique_ptr<AnyFilter> make_filter(const Motion& m, const robot::RangeBearingSensor& s,
                                       robot::LandmarkMap map, const std::string& proposal,
                                       const std::string& map_kind,
                                       const filter::FilterOptions& o) {
  if (proposal == "bootstrap" || proposal == "standard")
    return std::make_unique<FilterOf<Motion, filter::BootstrapProposal>>(
        m, s, std::move(map), filter::BootstrapProposal{}, o);
  require(proposal == "implicit",
          "ParticleFilter: proposal: expected 'implicit' or 'bootstrap', got '{}'", proposal);
  require(map_kind == "linear" || map_kind == "random",
          "ParticleFilter: map: expected 'linear' or 'random', got '{}'", map_kind);
  filter::ImplicitProposal p;
  p.map = map_kind == "random" ? filter::ImplicitMap::kRandom : filter::ImplicitMap::kLinear;
  return std::make_unique<FilterOf<Motion, filter::ImplicitProposal>>(m, s, std::move(map), p, o);
}

/// The Python object: the filter, the detections buffer reused across steps, the step count.
struct PyFilter {
  std::unique_ptr<AnyFilter> f;
  std::vector<LabelledMeasurement> z;
  robot::LandmarkMap map;  ///< the ids of the detections' column 0
  bool initialized = false;
};

/// Before initialize() the particles are zeros and the summary is empty: reading them would be
/// a silent wrong answer.
void require_initialized(const PyFilter& p, const char* what) {
  require(p.initialized, "ParticleFilter.{}: call initialize(mean, covariance) first", what);
}

py::dict summary(const StepSummary& s) {
  py::dict d;
  d["step"] = s.step;
  d["mean"] = py::array_t<double>(3, s.mean.data());
  d["covariance"] = py::array_t<double>({3, 3}, s.covariance.data());  // symmetric
  d["ess"] = s.ess;
  d["resampled"] = s.resampled;
  d["updated"] = s.updated;
  d["log_likelihood_increment"] = s.log_likelihood_increment;
  d["detections_used"] = s.detections_used;
  d["detections_dropped"] = s.detections_dropped;
  d["failures"] = s.failures;
  return d;
}

/// The largest landmark id: ids are C++ ints (robot::LandmarkMap, slam::Observation).
constexpr double kMaxLandmarkId = std::numeric_limits<int>::max();

/// The detections (k, 3) [landmark id or -1, range, bearing]: column 0 is refused unless it is
/// -1 (unlabelled) or an integer id in [0, 2^31 - 1]; a larger one would be cast to int out of
/// range (undefined behaviour), and read as unlabelled on common hardware.
void read_detections(const py::object& detections, std::vector<LabelledMeasurement>& z) {
  z.clear();
  if (detections.is_none()) return;
  const Array a = require_shape(detections, "detections", {-1, 3});
  for (py::ssize_t k = 0; k < a.shape(0); ++k) {
    const double id = a.at(k, 0);
    require(id == std::floor(id) && (id == -1 || (id >= 0 && id <= kMaxLandmarkId)),
            "detections: row {}: expected a landmark id in [0, {}] or -1 (unlabelled) in column "
            "0, got {}",
            k, kMaxLandmarkId, id);
    z.push_back({Measurement(a.at(k, 1), a.at(k, 2)), static_cast<int>(id)});
  }
}

/// A str argument whose value the library checks (with its own message): the type is checked
/// here, so that a number is refused naming the argument rather than with pybind11's TypeError.
std::string text_arg(const py::handle& o, const char* name) {
  require(py::isinstance<py::str>(o), "{}: expected a str, got {}", name, type_name(o));
  return o.cast<std::string>();
}

const robot::RangeBearingSensor& sensor_arg(const py::handle& o) {
  require(py::isinstance<robot::RangeBearingSensor>(o),
          "sensor: expected implicit.models.RangeBearing, got {}", type_name(o));
  return o.cast<const robot::RangeBearingSensor&>();
}

/// dt of step(), a number (0 keeps the previous step length); a negative one is refused by the
/// filter itself, with its message.
double step_length_arg(const py::handle& o) { return number_arg(o, "dt", -kUnbounded, kUnbounded); }

/// The map of a ParticleFilter: positions (K, 2) and, when given, their ids (K,) (else 0..K-1,
/// the rows).
robot::LandmarkMap filter_landmark_map(const py::object& landmarks, const py::object& ids) {
  if (ids.is_none()) return landmark_map(landmarks);
  const Array pos = require_shape(landmarks, "landmarks", {-1, 2});
  const Array id = require_shape(ids, "landmark_ids", {pos.shape(0)});
  robot::LandmarkMap map;
  for (py::ssize_t k = 0; k < pos.shape(0); ++k) {
    const double v = id.data()[k];
    require(v == std::floor(v) && v >= 0 && v <= kMaxLandmarkId,
            "landmark_ids: expected integer ids in [0, {}], got {} at index {}", kMaxLandmarkId, v,
            k);
    require(map.index_of(static_cast<int>(v)) < 0,
            "landmark_ids: expected unique ids, got {} at indices {} and {}", v,
            map.index_of(static_cast<int>(v)), k);
    map.add(static_cast<int>(v), robot::Landmark(pos.at(k, 0), pos.at(k, 1)));
  }
  return map;
}

/// The map's ids for a message: "0 to K-1" when they are the rows, else the first few.
std::string filter_map_ids_text(const robot::LandmarkMap& map) {
  bool rows = true;
  for (std::size_t k = 0; rows && k < map.size(); ++k) rows = map.id(k) == static_cast<int>(k);
  if (map.empty()) return "the map is empty";
  if (rows) return fmt::format("its ids are 0 to {}, the rows of `landmarks`", map.size() - 1);
  std::string ids;
  for (std::size_t k = 0; k < std::min<std::size_t>(map.size(), 8); ++k)
    ids += fmt::format("{}{}", k ? ", " : "", map.id(k));
  return fmt::format("its ids are those of `landmark_ids`: {}{}", ids,
                     map.size() > 8 ? ", ..." : "");
}

/// Labels of ParticleFilter detections, landmark ids, turned into the filter's map indices; an
/// id not in the map is refused (it would name another landmark, or none).
void ids_to_map_indices(const robot::LandmarkMap& map, std::vector<LabelledMeasurement>& z) {
  for (std::size_t k = 0; k < z.size(); ++k) {
    if (z[k].landmark < 0) continue;
    const int index = map.index_of(z[k].landmark);
    require(index >= 0,
            "detections: row {}: landmark id {} is not in the map ({}): column 0 takes landmark "
            "ids, or -1 (unlabelled)",
            k, z[k].landmark, filter_map_ids_text(map));
    z[k].landmark = index;
  }
}

constexpr const char* kParticleFilterDoc = R"doc(
Monte Carlo localization with a known landmark map (spec §3.8), stepped from Python.

ParticleFilter(model, sensor, landmarks, proposal="implicit", particles=100, seed=1,
               map="linear", resample_threshold=0.5, resampling="systematic", clutter=True,
               landmark_ids=None)

Args:
    model: implicit.models.Ute or implicit.models.Unicycle.
    sensor: implicit.models.RangeBearing.
    landmarks: (K, 2) landmark positions [m].
    proposal: "implicit" (implicit sampling per particle) or "bootstrap" (the motion model).
    particles: M.
    seed: particle j at step n draws from the stream (seed, n, j): results do not depend on
        the number of threads, and equal those of `implicit mcl` run r with seed * runs + r.
    map: the implicit proposal's map, "linear" or "random".
    resample_threshold: resample when ESS < threshold * M.
    resampling: "multinomial", "systematic", "stratified" or "residual".
    clutter: detections outside the gate contribute the clutter density.
    landmark_ids: (K,) the landmarks' ids (integers >= 0, unique), e.g. log.landmark_ids or
        the ids of slam.Filter.map(); None: 0 to K-1, the rows of landmarks.

Use: initialize(mean (3,), covariance (3, 3)), then step(control (2,), dt [s], detections) per
motion step, with detections an (k, 3) array of [landmark id or -1, range m, bearing rad] (None
or k = 0: predict only); dt = 0 keeps the previous step length (initially the model's dt).
Column 0 is a landmark id, as in slam.Filter and Log.scans: with landmark_ids=None the id is
the row of landmarks (as in Steps.detections); an id not in the map raises ValueError, -1 is an
unlabelled detection (associated by the filter).

particles (M, 3) and weights (M,) are read-only views of the filter's buffers, valid until the
next step (copy them to keep them). mean() and covariance() are the weighted pose mean (heading:
circular mean) and covariance; ess the effective sample size of the last update; last a dict
summary of the last step.

Example::

    steps = implicit.data.steps(implicit.data.carpark(), implicit.models.Ute())
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(),
                                 steps.landmarks, particles=100, seed=1)
    pf.initialize(steps.initial_mean, steps.initial_covariance)
    for u, dt, z in zip(steps.controls, steps.dt, steps.detections):
        pf.step(u, dt, z)
    print(pf.mean()))doc";

void bind_particle_filter(py::module_& m) {
  py::class_<PyFilter>(m, "ParticleFilter", kParticleFilterDoc)
      .def(
          py::init([](const py::object& model, const py::object& sensor_in,
                      const py::object& landmarks, const py::object& proposal_in,
                      const py::object& particles, const py::object& seed, const py::object& map_in,
                      const py::object& resample_threshold, const py::object& resampling,
                      const py::object& clutter, const py::object& landmark_ids) {
            const robot::RangeBearingSensor& sensor = sensor_arg(sensor_in);
            const std::string proposal = text_arg(proposal_in, "proposal");
            const std::string map = text_arg(map_in, "map");
            filter::FilterOptions o;
            o.particles =
                particle_count_arg(particles, "particles", kMaxParticles, kPoseParticleBytes);
            o.seed = seed_arg(seed, "seed");
            o.resample_threshold = number_arg(resample_threshold, "resample_threshold", 0.0, 1.0);
            o.resampling = parse_resampling_scheme(choice_arg(
                resampling, "resampling", {"multinomial", "systematic", "stratified", "residual"}));
            o.association.clutter = bool_arg(clutter, "clutter");
            robot::LandmarkMap lm = filter_landmark_map(landmarks, landmark_ids);
            PyFilter p;
            p.map = lm;
            if (py::isinstance<robot::UnicycleModel>(model))
              p.f = make_filter(model.cast<const robot::UnicycleModel&>(), sensor, std::move(lm),
                                proposal, map, o);
            else if (py::isinstance<robot::UteModel>(model))
              p.f = make_filter(model.cast<const robot::UteModel&>(), sensor, std::move(lm),
                                proposal, map, o);
            else
              throw InvalidArgument(fmt::format(
                  "ParticleFilter: model: expected implicit.models.Ute or Unicycle, got {}",
                  std::string(py::str(py::type::handle_of(model).attr("__name__")))));
            return p;
          }),
          py::arg("model"), py::arg("sensor"), py::arg("landmarks"),
          py::arg("proposal") = "implicit", py::arg("particles") = 100, py::arg("seed") = 1,
          py::arg("map") = "linear", py::arg("resample_threshold") = 0.5,
          py::arg("resampling") = "systematic", py::arg("clutter") = true,
          py::arg("landmark_ids") = py::none())
      .def(
          "initialize",
          [](PyFilter& p, const py::object& mean, const py::object& cov) {
            const Array a = require_shape(mean, "mean", {3});
            const Array c = require_shape(cov, "covariance", {3, 3});
            Mat<3> cm;
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) cm(i, j) = c.at(i, j);
            p.f->initialize(Pose(a.data()[0], a.data()[1], a.data()[2]), cm);
            p.initialized = true;
          },
          py::arg("mean"), py::arg("covariance"),
          "Draws the particles from N(mean (3,), covariance (3, 3)) with equal weights.")
      .def(
          "step",
          [](PyFilter& p, const py::object& control, const py::object& dt_in,
             const py::object& detections) {
            require_initialized(p, "step");
            const double dt = step_length_arg(dt_in);
            const Array u = require_shape(control, "control", {2});
            read_detections(detections, p.z);
            ids_to_map_indices(p.map, p.z);
            const Control c(u.data()[0], u.data()[1]);
            {
              py::gil_scoped_release unlocked;
              if (dt != 0) p.f->set_step_length(dt);
              p.f->step(c, p.z);
            }
          },
          py::arg("control"), py::arg("dt") = 0.0, py::arg("detections") = py::none(),
          "One motion step with control (2,) over dt [s] (0: the previous length), then the "
          "update with detections (k, 3) [landmark id or -1, range m, bearing rad] (None: "
          "predict); the ids are those of the map (landmark_ids, else the rows of landmarks).")
      .def_property_readonly("particles",
                             [](py::object self) {
                               const PyFilter& p = self.cast<const PyFilter&>();
                               require_initialized(p, "particles");
                               const auto s = p.f->particles();
                               py::array_t<double> a(
                                   {static_cast<py::ssize_t>(s.size()), py::ssize_t{3}},
                                   s.data()->data(), self);
                               a.attr("flags").attr("writeable") = false;
                               return a;
                             })
      .def_property_readonly("weights",
                             [](py::object self) {
                               const PyFilter& p = self.cast<const PyFilter&>();
                               require_initialized(p, "weights");
                               const auto w = p.f->weights();
                               py::array_t<double> a(static_cast<py::ssize_t>(w.size()), w.data(),
                                                     self);
                               a.attr("flags").attr("writeable") = false;
                               return a;
                             })
      .def("mean",
           [](const PyFilter& p) {
             require_initialized(p, "mean");
             return py::array_t<double>(3, p.f->last().mean.data());
           })
      .def("covariance",
           [](const PyFilter& p) {
             require_initialized(p, "covariance");
             return py::array_t<double>({3, 3}, p.f->last().covariance.data());
           })
      .def_property_readonly("ess",
                             [](const PyFilter& p) {
                               require_initialized(p, "ess");
                               return p.f->last().ess;
                             })
      .def_property_readonly("last", [](const PyFilter& p) {
        require_initialized(p, "last");
        return summary(p.f->last());
      });
}

struct PySlam {
  std::unique_ptr<slam::SlamFilter> f;
  std::vector<slam::Observation> z;
  std::uint64_t n = 0;
};

constexpr const char* kSlamFilterDoc = R"doc(
Online landmark SLAM (spec §3.5, paper §4.2), stepped from Python.

Filter(method="implicit-rb", particles=100, seed=1, model=None, sensor=RangeBearing(),
       association="known", initial_pose=(0, 0, 0))

Args:
    method: "ekf", "fastslam1", "fastslam2", "implicit" or "implicit-rb".
    particles: M (ignored by "ekf").
    seed: filter randomness (seed, step, particle).
    model: implicit.models.Ute (default: the Car Park Ute) or implicit.models.Unicycle.
    sensor: implicit.models.RangeBearing (Sigma2).
    association: "known" (column 0 of the detections identifies the landmark) or "ml".
    initial_pose: (3,) the known start pose.

step(control (2,), dt [s], detections (k, 3) [landmark id or -1, range m, bearing rad] or
None): column 0 is the landmark's id (an integer in [0, 2^31 - 1]), as in ParticleFilter
(association "ml": -1 marks an unlabelled row);
mean() (3,), covariance() (3, 3); map() returns (positions (K, 2), ids (K,)); ess the mean
ESS / M over the weighted steps so far.)doc";

void bind_slam_filter(py::module_& m) {
  py::class_<PySlam>(m, "Filter", kSlamFilterDoc)
      .def(py::init([](const py::object& method, const py::object& particles,
                       const py::object& seed, const py::object& model, const py::object& sensor,
                       const py::object& association, const py::object& initial_pose) {
             slam::SlamOptions o;
             o.method = slam::parse_slam_method(text_arg(method, "method"));
             o.association = slam::parse_association(text_arg(association, "association"));
             // The tool's cap (`implicit slam --particles`); the pose is what a particle costs
             // at least, its map grows with the landmarks.
             o.particles = static_cast<int>(
                 particle_count_arg(particles, "particles", kMaxSlamParticles, kPoseParticleBytes));
             o.seed = seed_arg(seed, "seed");
             o.sensor = sensor_arg(sensor);
             if (py::isinstance<robot::UnicycleModel>(model))
               o.model = robot::AnyMotionModel(model.cast<const robot::UnicycleModel&>());
             else if (py::isinstance<robot::UteModel>(model))
               o.motion = model.cast<const robot::UteModel&>().params();
             else
               require(model.is_none(),
                       "model: expected implicit.models.Ute, implicit.models.Unicycle or None, "
                       "got {}",
                       type_name(model));
             o.validate();
             const Array x0 = require_shape(initial_pose, "initial_pose", {3});
             PySlam p;
             p.f = slam::make_slam_filter(o, Pose(x0.data()[0], x0.data()[1], x0.data()[2]));
             return p;
           }),
           py::arg("method") = "implicit-rb", py::arg("particles") = 100, py::arg("seed") = 1,
           py::arg("model") = py::none(), py::arg("sensor") = robot::RangeBearingSensor(),
           py::arg("association") = "known",
           py::arg("initial_pose") = py::array_t<double>(3, Pose::Zero().eval().data()))
      .def(
          "step",
          [](PySlam& p, const py::object& control, const py::object& dt_in,
             const py::object& detections) {
            const double dt = step_length_arg(dt_in);
            const Array u = require_shape(control, "control", {2});
            std::vector<LabelledMeasurement> z;
            read_detections(detections, z);
            p.z.clear();
            for (const auto& d : z) p.z.push_back({d.z, d.landmark});
            const Control c(u.data()[0], u.data()[1]);
            py::gil_scoped_release unlocked;
            if (dt != 0) p.f->set_step_length(dt);
            p.f->step(++p.n, c, p.z);
          },
          py::arg("control"), py::arg("dt") = 0.0, py::arg("detections") = py::none(),
          "One motion step with control (2,) over dt [s] (0: the previous length), then the "
          "detections (k, 3) [landmark, range m, bearing rad] (None: predict only).")
      .def("mean",
           [](const PySlam& p) {
             const Pose x = p.f->pose().mean;
             return py::array_t<double>(3, x.data());
           })
      .def("covariance",
           [](const PySlam& p) {
             const Mat<3> c = p.f->pose().cov;
             return py::array_t<double>({3, 3}, c.data());
           })
      .def(
          "map",
          [](const PySlam& p) {
            const slam::MapEstimate e = p.f->map();
            py::array_t<int> ids(static_cast<py::ssize_t>(e.ids.size()), e.ids.data());
            py::array_t<double> pos({static_cast<py::ssize_t>(e.landmarks.size()), py::ssize_t{2}});
            for (std::size_t k = 0; k < e.landmarks.size(); ++k) {
              pos.mutable_at(k, 0) = e.landmarks[k](0);
              pos.mutable_at(k, 1) = e.landmarks[k](1);
            }
            return py::make_tuple(pos, ids);
          })
      .def_property_readonly("ess",
                             [](const PySlam& p) { return p.f->stats().mean_ess_fraction(); });
}

}  // namespace

void init_filter(py::module_& m) { bind_particle_filter(m); }
void init_slam(py::module_& m) { bind_slam_filter(m); }

}  // namespace implicit::python
