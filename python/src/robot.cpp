// implicit.models and implicit.data: the Ute and unicycle motion models, the range-bearing
// sensor, robot logs (read, simulated, the bundled data sets) and logs prepared for filtering.

#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "common.hpp"
#include "implicit/implicit.hpp"
#include "robot.hpp"

namespace implicit::python {
namespace {

using robot::Landmark;
using robot::Measurement;
using robot::Pose;

Vec<2> vec2(const py::object& o, const std::string& name) {
  const Array a = require_shape(o, name, {2});
  return {a.data()[0], a.data()[1]};
}
Vec<3> vec3(const py::object& o, const std::string& name) {
  const Array a = require_shape(o, name, {3});
  return {a.data()[0], a.data()[1], a.data()[2]};
}
py::array_t<double> numpy_matrix(const Eigen::MatrixXd& m) {
  // Eigen is column-major; the copy is row-major (the numpy default) and small.
  py::array_t<double> a({m.rows(), m.cols()});
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) a.mutable_at(i, j) = m(i, j);
  return a;
}
py::array_t<double> numpy_vec3(const Vec<3>& v) { return py::array_t<double>(3, v.data()); }

py::array_t<double> points(const std::vector<Landmark>& p) {
  py::array_t<double> a({static_cast<py::ssize_t>(p.size()), py::ssize_t{2}});
  for (std::size_t k = 0; k < p.size(); ++k) {
    a.mutable_at(k, 0) = p[k](0);
    a.mutable_at(k, 1) = p[k](1);
  }
  return a;
}

template <typename Model>
void bind_motion(py::class_<Model>& c) {
  c.def_property_readonly("dt", &Model::dt, "Nominal step length [s].")
      .def(
          "predict",
          [](const Model& m, const py::object& x, const py::object& u, double dt) {
            const Model s = dt > 0 ? m.with_dt(dt) : m;
            return numpy_vec3(s.predict(vec3(x, "x"), vec2(u, "u")));
          },
          py::arg("x"), py::arg("u"), py::arg("dt") = 0.0,
          "Noise-free next pose (3,) from pose x (3,) [m, m, rad] and control u (2,); dt [s] "
          "overrides the nominal step length when > 0.")
      .def(
          "process_covariance",
          [](const Model& m, const py::object& x, const py::object& u, double dt) {
            const Model s = dt > 0 ? m.with_dt(dt) : m;
            return numpy_matrix(Eigen::MatrixXd(s.process_covariance(vec3(x, "x"), vec2(u, "u"))));
          },
          py::arg("x"), py::arg("u"), py::arg("dt") = 0.0,
          "Covariance (3, 3) of the process noise of one step (Sigma1, spec §3.1).")
      .def(
          "jacobian_state",
          [](const Model& m, const py::object& x, const py::object& u) {
            return numpy_matrix(Eigen::MatrixXd(m.jacobian_state(vec3(x, "x"), vec2(u, "u"))));
          },
          py::arg("x"), py::arg("u"), "Jacobian (3, 3) of predict with respect to x.")
      .def_property_readonly("control_std",
                             [](const Model& m) {
                               return py::make_tuple(m.params().control_std(0),
                                                     m.params().control_std(1));
                             })
      .def_property_readonly("state_std", [](const Model& m) {
        const Vec<3>& q = m.params().state_std;
        return py::make_tuple(q(0), q(1), q(2));
      });
}

py::object optional_vec(const py::object& o, const char* name, int n) {
  if (o.is_none()) return o;
  require_shape(o, name, {n});
  return o;
}

void bind_models(py::module_& m) {
  py::class_<robot::UteModel> ute(m, "Ute", R"doc(
The Ute (car-like vehicle of the Car Park data set, spec §3.1), pose (x [m], y [m], heading [rad]),
control (axle speed [m/s], steering angle [rad]).

Parameters: dt [s] nominal step (0.025), control_std (2,) std of speed and steering (0.5, 0.5),
state_std (3,) Q std of x, y [m] and heading [rad]; wheelbase, encoder_offset, laser_forward,
laser_left [m] (Table 7).

Example: ``implicit.models.Ute(control_std=(0.1, 0.1)).predict([0, 0, 0], [1.0, 0.0])``)doc");
  ute.def(py::init([](double dt, const py::object& control_std, const py::object& state_std,
                      double wheelbase, double encoder_offset, double laser_forward,
                      double laser_left) {
            robot::UteParams p;
            p.dt = dt;
            if (!optional_vec(control_std, "control_std", 2).is_none())
              p.control_std = vec2(control_std, "control_std");
            if (!optional_vec(state_std, "state_std", 3).is_none())
              p.state_std = vec3(state_std, "state_std");
            p.wheelbase = wheelbase;
            p.encoder_offset = encoder_offset;
            p.laser_forward = laser_forward;
            p.laser_left = laser_left;
            return robot::UteModel(p);
          }),
          py::arg("dt") = 0.025, py::arg("control_std") = py::none(),
          py::arg("state_std") = py::none(), py::arg("wheelbase") = 2.83,
          py::arg("encoder_offset") = 0.76, py::arg("laser_forward") = 3.78,
          py::arg("laser_left") = 0.5);
  bind_motion(ute);
  ute.def("__repr__", [](const robot::UteModel& u) {
    return fmt::format("Ute(dt={}, control_std=({}, {}))", u.dt(), u.params().control_std(0),
                       u.params().control_std(1));
  });

  py::class_<robot::UnicycleModel> uni(m, "Unicycle", R"doc(
The unicycle: pose (x [m], y [m], heading [rad]), control (v [m/s], omega [rad/s]).

Parameters: dt [s] nominal step (0.1), control_std (2,) std of v and omega (0.1, 0.05), state_std
(3,) Q std per sqrt(s) of x, y [m] and heading [rad].

Example: ``implicit.models.Unicycle().predict([0, 0, 0], [1.0, 0.1])``)doc");
  uni.def(py::init([](double dt, const py::object& control_std, const py::object& state_std) {
            robot::UnicycleParams p;
            p.dt = dt;
            if (!optional_vec(control_std, "control_std", 2).is_none())
              p.control_std = vec2(control_std, "control_std");
            if (!optional_vec(state_std, "state_std", 3).is_none())
              p.state_std = vec3(state_std, "state_std");
            return robot::UnicycleModel(p);
          }),
          py::arg("dt") = 0.1, py::arg("control_std") = py::none(),
          py::arg("state_std") = py::none());
  bind_motion(uni);
  uni.def("__repr__",
          [](const robot::UnicycleModel& u) { return fmt::format("Unicycle(dt={})", u.dt()); });

  py::class_<robot::RangeBearingSensor>(m, "RangeBearing", R"doc(
The range-bearing sensor z = (range [m], bearing [rad]) of a landmark (spec §3.2), noise
Sigma2 = diag(range_variance [m^2], bearing_variance [rad^2]).

Example: ``s = implicit.models.RangeBearing.from_std(0.1, 0.01); s.predict([0, 0, 0], [3, 4])``)doc")
      .def(py::init<double, double>(), py::arg("range_variance") = 0.05,
           py::arg("bearing_variance") = 0.05 * kPi / 180.0)
      .def_static("from_std", &robot::RangeBearingSensor::from_std, py::arg("range_std"),
                  py::arg("bearing_std"), "Sigma2 from standard deviations [m], [rad].")
      .def_property_readonly(
          "noise_covariance",
          [](const robot::RangeBearingSensor& s) {
            return numpy_matrix(Eigen::MatrixXd(s.noise_covariance()));
          },
          "Sigma2 (2, 2).")
      .def(
          "predict",
          [](const robot::RangeBearingSensor& s, const py::object& x, const py::object& l) {
            const Measurement z = s.predict(vec3(x, "x"), vec2(l, "landmark"));
            return py::array_t<double>(2, z.data());
          },
          py::arg("x"), py::arg("landmark"),
          "Noise-free (range, bearing) (2,) of landmark (2,) seen from pose x (3,).");
}

}  // namespace

robot::LandmarkMap landmark_map(const py::object& o) {
  const Array a = require_shape(o, "landmarks", {-1, 2});
  robot::LandmarkMap map;
  for (py::ssize_t k = 0; k < a.shape(0); ++k)
    map.add(static_cast<int>(k), robot::Landmark(a.at(k, 0), a.at(k, 1)));
  return map;
}

py::array_t<double> landmark_points(const robot::LandmarkMap& map) {
  return points(map.positions());
}

void init_models(py::module_& m) { bind_models(m); }

}  // namespace implicit::python
