// The compiled part of the Python package `implicit` (implicit._implicit). The public API, its
// docstrings and argument defaults live in the pure-Python package python/implicit/, which calls
// these functions; C++ errors (InvalidArgument, ParseError) arrive as Python exceptions with the
// C++ message.

#include "common.hpp"
#include "implicit/core/version.hpp"

namespace implicit::python {
void init_core(py::module_& m);
void init_models(py::module_& m);
void init_motion_registry(py::module_& m);
void init_data(py::module_& m);
void init_bag(py::module_& m);
void init_filter(py::module_& m);
void init_slam(py::module_& m);
void init_grid_slam(py::module_& m);
void init_runs(py::module_& m);
void init_control(py::module_& m);
void init_laser(py::module_& m);
void init_eval(py::module_& m);
void init_user_model(py::module_& m);
void init_da(py::module_& m);
}  // namespace implicit::python

PYBIND11_MODULE(_implicit, m) {
  namespace ip = implicit::python;
  m.doc() = "Compiled core of the implicit package (use `import implicit`).";
  // ValueError subclasses: `except ValueError` catches them, the message is the C++ one.
  pybind11::register_exception<implicit::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);
  pybind11::register_exception<implicit::ParseError>(m, "ParseError", PyExc_ValueError);
  ip::init_core(m);
  auto models = m.def_submodule("models", "Motion and sensor models.");
  ip::init_models(models);
  ip::init_motion_registry(models);
  auto data = m.def_submodule("data", "Robot logs and data sets.");
  ip::init_data(data);
  ip::init_bag(data);
  ip::init_filter(m);
  auto slam = m.def_submodule("slam", "SLAM filters.");
  ip::init_slam(slam);
  ip::init_grid_slam(slam);
  ip::init_runs(m);
  auto control = m.def_submodule("control", "Path integral control problems.");
  ip::init_control(control);
  auto laser = m.def_submodule("laser", "Laser localization on occupancy grids.");
  ip::init_laser(laser);
  auto eval = m.def_submodule("eval", "Trajectory scoring: APE and RPE.");
  ip::init_eval(eval);
  ip::init_user_model(m);
  auto da = m.def_submodule("da", "Data assimilation: the Lorenz models and `implicit da`.");
  ip::init_da(da);
  m.attr("__version__") = implicit::version();
}
