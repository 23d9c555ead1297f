// implicit.data: robot logs (the text format of docs/formats.md, the bundled Car Park and
// Victoria Park data, simulated logs) and a log prepared for step-by-step filtering.

#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "common.hpp"
#include "experiments/vehicle.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/carpark.hpp"
#include "implicit/robot/simulate.hpp"
#include "robot.hpp"

namespace implicit::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// (k, 3) array of [landmark, range, bearing] rows.
template <typename Rows, typename Fn>
py::array_t<double> rows3(const Rows& rows, Fn row) {
  py::array_t<double> a({static_cast<py::ssize_t>(rows.size()), py::ssize_t{3}});
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto [id, r, b] = row(rows[k]);
    a.mutable_at(k, 0) = id;
    a.mutable_at(k, 1) = r;
    a.mutable_at(k, 2) = b;
  }
  return a;
}

void bind_log(py::module_& m) {
  py::class_<robot::RobotLog>(m, "Log", R"doc(
A robot log (docs/formats.md): landmarks, an initial pose prior, timed controls, scans of
range-bearing detections and ground truth. Arrays are copies (the log keeps its own data).

Attributes: landmarks (K, 2) [m], landmark_ids (K,), control_times (N,) [s], controls (N, 2),
scans (list of (time [s], (k, 3) array of [landmark id or -1, range m, bearing rad])),
truth_times (T,), truth (T, 2) [m], truth_heading (T,) [rad, NaN where absent],
initial_mean (3,), initial_std (3,), vehicle (model name or None).

Example: ``log = implicit.data.carpark(); log.controls.shape``)doc")
      .def_property_readonly("landmarks",
                             [](const robot::RobotLog& l) { return landmark_points(l.landmarks); })
      .def_property_readonly("landmark_ids",
                             [](const robot::RobotLog& l) {
                               std::vector<int> ids;
                               for (std::size_t k = 0; k < l.landmarks.size(); ++k)
                                 ids.push_back(l.landmarks.id(k));
                               return py::array_t<int>(static_cast<py::ssize_t>(ids.size()),
                                                       ids.data());
                             })
      .def_property_readonly("control_times",
                             [](const robot::RobotLog& l) {
                               py::array_t<double> a(static_cast<py::ssize_t>(l.controls.size()));
                               for (std::size_t k = 0; k < l.controls.size(); ++k)
                                 a.mutable_at(k) = l.controls[k].time;
                               return a;
                             })
      .def_property_readonly(
          "controls",
          [](const robot::RobotLog& l) {
            py::array_t<double> a({static_cast<py::ssize_t>(l.controls.size()), py::ssize_t{2}});
            for (std::size_t k = 0; k < l.controls.size(); ++k) {
              a.mutable_at(k, 0) = l.controls[k].u(0);
              a.mutable_at(k, 1) = l.controls[k].u(1);
            }
            return a;
          })
      .def_property_readonly("scans",
                             [](const robot::RobotLog& l) {
                               py::list out;
                               for (const auto& s : l.scans)
                                 out.append(py::make_tuple(
                                     s.time, rows3(s.observations, [](const robot::Observation& o) {
                                       return std::tuple<double, double, double>(o.landmark_id,
                                                                                 o.z(0), o.z(1));
                                     })));
                               return out;
                             })
      .def_property_readonly("truth_times",
                             [](const robot::RobotLog& l) {
                               py::array_t<double> a(static_cast<py::ssize_t>(l.truth.size()));
                               for (std::size_t k = 0; k < l.truth.size(); ++k)
                                 a.mutable_at(k) = l.truth[k].time;
                               return a;
                             })
      .def_property_readonly(
          "truth",
          [](const robot::RobotLog& l) {
            py::array_t<double> a({static_cast<py::ssize_t>(l.truth.size()), py::ssize_t{2}});
            for (std::size_t k = 0; k < l.truth.size(); ++k) {
              a.mutable_at(k, 0) = l.truth[k].position(0);
              a.mutable_at(k, 1) = l.truth[k].position(1);
            }
            return a;
          })
      .def_property_readonly("truth_heading",
                             [](const robot::RobotLog& l) {
                               py::array_t<double> a(static_cast<py::ssize_t>(l.truth.size()));
                               for (std::size_t k = 0; k < l.truth.size(); ++k)
                                 a.mutable_at(k) = l.truth[k].heading.value_or(kNaN);
                               return a;
                             })
      .def_property_readonly("initial_mean",
                             [](const robot::RobotLog& l) -> py::object {
                               if (!l.initial) return py::none();
                               return py::array_t<double>(3, l.initial->mean.data());
                             })
      .def_property_readonly("initial_std",
                             [](const robot::RobotLog& l) -> py::object {
                               if (!l.initial) return py::none();
                               return py::array_t<double>(3, l.initial->std.data());
                             })
      .def_property_readonly("vehicle",
                             [](const robot::RobotLog& l) -> py::object {
                               if (!l.vehicle) return py::none();
                               return py::str(l.vehicle->model);
                             })
      .def(
          "write",
          [](const robot::RobotLog& l, const std::string& path) {
            robot::write_robot_log(std::filesystem::path(path), l);
          },
          py::arg("path"), "Writes the log in the text format (gzip when the name ends in .gz).")
      .def("__repr__", [](const robot::RobotLog& l) {
        return fmt::format("<implicit.data.Log: {} controls, {} scans, {} landmarks>",
                           l.controls.size(), l.scans.size(), l.landmarks.size());
      });
}

void bind_problem(py::module_& m) {
  py::class_<filter::LocalizationProblem>(m, "Steps", R"doc(
A log prepared for filtering, one entry per motion step (what ``implicit mcl`` runs).

Attributes: controls (N, 2), dt (N,) step lengths [s], detections (list of N arrays (k, 3) of
[landmark id, range m, bearing rad], the id being the row of `landmarks` (the log's own ids are
renumbered 0 to K-1); k = 0 at prediction-only steps), truth (N, 2) [m] and
truth_heading (N,) [rad] interpolated at the steps (NaN where unknown), landmarks (K, 2),
initial_mean (3,), initial_covariance (3, 3).

Example::

    steps = implicit.data.steps(implicit.data.carpark(), implicit.models.Ute())
    for u, dt, z in zip(steps.controls, steps.dt, steps.detections): ...)doc")
      .def_property_readonly(
          "controls",
          [](const filter::LocalizationProblem& p) {
            const auto& s = p.schedule.steps;
            py::array_t<double> a({static_cast<py::ssize_t>(s.size()), py::ssize_t{2}});
            for (std::size_t k = 0; k < s.size(); ++k) {
              a.mutable_at(k, 0) = s[k].u(0);
              a.mutable_at(k, 1) = s[k].u(1);
            }
            return a;
          })
      .def_property_readonly("dt",
                             [](const filter::LocalizationProblem& p) {
                               return py::array_t<double>(
                                   static_cast<py::ssize_t>(p.step_dt.size()), p.step_dt.data());
                             })
      .def_property_readonly("detections",
                             [](const filter::LocalizationProblem& p) {
                               py::list out;
                               for (const auto& d : p.detections)
                                 out.append(rows3(d, [](const filter::LabelledMeasurement& z) {
                                   return std::tuple<double, double, double>(z.landmark, z.z(0),
                                                                             z.z(1));
                                 }));
                               return out;
                             })
      .def_property_readonly(
          "truth",
          [](const filter::LocalizationProblem& p) {
            const auto& t = p.truth.position;
            py::array_t<double> a({static_cast<py::ssize_t>(t.size()), py::ssize_t{2}});
            for (std::size_t k = 0; k < t.size(); ++k) {
              a.mutable_at(k, 0) = t[k](0);
              a.mutable_at(k, 1) = t[k](1);
            }
            return a;
          })
      .def_property_readonly("truth_heading",
                             [](const filter::LocalizationProblem& p) {
                               return py::array_t<double>(
                                   static_cast<py::ssize_t>(p.truth.heading.size()),
                                   p.truth.heading.data());
                             })
      .def_property_readonly(
          "landmarks", [](const filter::LocalizationProblem& p) { return landmark_points(p.map); })
      .def_property_readonly("initial_mean",
                             [](const filter::LocalizationProblem& p) {
                               return py::array_t<double>(3, p.initial_mean.data());
                             })
      .def_property_readonly("initial_covariance",
                             [](const filter::LocalizationProblem& p) {
                               // Symmetric: the column-major buffer reads the same row-major.
                               return py::array_t<double>({3, 3}, p.initial_covariance.data());
                             })
      .def("__len__", [](const filter::LocalizationProblem& p) { return p.schedule.steps.size(); });
}

/// The model argument must be one of the two motion models (a clear error, not a cast failure).
void require_model(const py::object& model, const char* where) {
  require(py::isinstance<robot::UteModel>(model) || py::isinstance<robot::UnicycleModel>(model),
          "{}: model: expected implicit.models.Ute or implicit.models.Unicycle, got {}", where,
          std::string(py::str(py::type::handle_of(model).attr("__name__"))));
}

template <typename Model>
robot::RobotLog simulate_with(const Model& model, const robot::RangeBearingSensor& sensor,
                              const robot::SimulationOptions& o, double speed, bool unicycle,
                              std::uint64_t seed) {
  auto log = robot::simulate_robot_log(
      model, sensor, robot::square_route_driver(speed, o.route_side, unicycle), o, seed);
  log.vehicle = robot::declare_vehicle(model.params());
  return log;
}

}  // namespace

void init_data(py::module_& m) {
  bind_log(m);
  bind_problem(m);
  m.def(
      "read_log", [](const std::string& path) { return robot::read_robot_log(path); },
      py::arg("path"), "Reads a robot log in the text format (docs/formats.md; .gz accepted).");
  m.def(
      "carpark",
      []() {
        // The Car Park conversion uses the Ute's geometry (laser offset, encoder offset).
        return robot::carpark_to_log(robot::load_carpark(robot::default_carpark_dir()),
                                     robot::UteModel());
      },
      "The University of Sydney Car Park data set (paper §4.1) as a robot log: 15 surveyed "
      "beacons, 40 Hz controls, laser detections and GPS truth.");
  m.def(
      "victoria_park",
      []() {
        return robot::read_robot_log(find_share_dir("data", "IMPLICIT_DATA_DIR") / "victoria_park" /
                                     "victoria_park.log.gz");
      },
      "The Victoria Park data set (bundled log, data/victoria_park/README.md).");
  m.def(
      "steps",
      [](const robot::RobotLog& log, const py::object& model) {
        require_model(model, "steps");
        const bool unicycle = py::isinstance<robot::UnicycleModel>(model);
        // The tool's check (experiments/vehicle.cpp, `implicit mcl --model`): a log drives one
        // robot, and the other model would read its controls as something else.
        experiments::resolve_model("steps", unicycle ? "unicycle" : "ute",
                                   log.vehicle ? std::optional(log.vehicle->model) : std::nullopt,
                                   log.source.empty() ? std::string("(in memory)") : log.source);
        const double dt = unicycle ? model.cast<const robot::UnicycleModel&>().dt()
                                   : model.cast<const robot::UteModel&>().dt();
        return filter::make_problem(log, dt);
      },
      py::arg("log"), py::arg("model"),
      "The log as filter steps at the model's nominal dt (scans attached to the nearest step). "
      "A log that declares a vehicle (Log.vehicle) takes that model only, as `implicit mcl "
      "--model` does: another one raises ValueError.");
  m.def(
      "simulate",
      [](const py::object& model, const py::object& sensor_in, const py::object& steps,
         const py::object& landmarks, const py::object& scan_every, const py::object& max_range,
         const py::object& speed, const py::object& seed_in) {
        require_model(model, "simulate");
        require(py::isinstance<robot::RangeBearingSensor>(sensor_in),
                "sensor: expected implicit.models.RangeBearing, got {}", type_name(sensor_in));
        const auto& sensor = sensor_in.cast<const robot::RangeBearingSensor&>();
        // The ranges of `implicit simulate`'s flags (apps/cmd_simulate.cpp).
        robot::SimulationOptions o;
        o.steps = static_cast<int>(int_arg(steps, "steps", 1, 10'000'000));
        o.landmarks = static_cast<int>(int_arg(landmarks, "landmarks", 1, 100'000));
        o.scan_every = static_cast<int>(int_arg(scan_every, "scan_every", 1, 100'000));
        o.max_range = number_arg(max_range, "max_range", 0.0, kUnbounded, /*lo_open=*/true);
        const std::uint64_t seed = seed_arg(seed_in, "seed");
        const bool unicycle = py::isinstance<robot::UnicycleModel>(model);
        const double v = speed.is_none() ? (unicycle ? 1.0 : 3.0)
                                         : number_arg(speed, "speed", 0.0, kUnbounded, true);
        if (unicycle)
          return simulate_with(model.cast<const robot::UnicycleModel&>(), sensor, o, v, true, seed);
        return simulate_with(model.cast<const robot::UteModel&>(), sensor, o, v, false, seed);
      },
      py::arg("model"), py::arg("sensor"), py::arg("steps") = 1200, py::arg("landmarks") = 40,
      py::arg("scan_every") = 3, py::arg("max_range") = 15.0, py::arg("speed") = py::none(),
      py::arg("seed") = 1,
      "A simulated drive around a 40 m square among random landmarks (robot/simulate.hpp): "
      "`steps` controls with lengths uniform in [0.5, 1.5] x dt, a scan every `scan_every` "
      "steps up to `max_range` [m], speed [m/s] (default 3 for the Ute, 1 for the unicycle), as "
      "`implicit simulate`.");
}

}  // namespace implicit::python
