// implicit.models.register_motion_model and motion_models: a motion model written in Python,
// registered by name in the tools' registry (experiments/motion_models.hpp), so that
// implicit.mcl.run(model=...), implicit.slam.run(model=...) and logs declaring `vehicle NAME`
// run it as they run a built-in. The filters call it per particle from their worker threads:
// each call takes the GIL (the runners release it), so a Python model is correct, not fast.

#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "common.hpp"
#include "experiments/motion_models.hpp"

namespace implicit::python {
namespace {

using robot::Control;
using robot::Mat3;
using robot::Pose;

/// The callbacks of one registered model. Never freed: the registry keeps its entries for the
/// life of the process, and freeing Python objects needs the interpreter, which is gone by the
/// time the process's statics are destroyed.
struct MotionCallbacks {
  std::string name;
  py::object predict, covariance, jacobian;  ///< jacobian: None for finite differences
};

py::array_t<double> numpy_of(const double* data, py::ssize_t n) {
  return py::array_t<double>(n, data);
}

class PythonMotionModel {
 public:
  PythonMotionModel(const MotionCallbacks* cb, double dt, Vec<2> control_sd, Vec<3> state_sd)
      : cb_(cb), dt_(dt), control_sd_(std::move(control_sd)), state_sd_(std::move(state_sd)) {}

  double dt() const { return dt_; }
  PythonMotionModel with_dt(double dt) const { return {cb_, dt, control_sd_, state_sd_}; }

  Pose predict(const Pose& x, const Control& u) const {
    py::gil_scoped_acquire gil;
    const Array a = checked(call("predict", cb_->predict, x, u), "predict", {3});
    return {a.data()[0], a.data()[1], a.data()[2]};
  }
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    py::gil_scoped_acquire gil;
    const Array a = checked(call("process_covariance", cb_->covariance, x, u, true),
                            "process_covariance", {3, 3});
    return matrix(a);
  }
  Mat3 jacobian_state(const Pose& x, const Control& u) const {
    if (cb_->jacobian.is_none()) return differenced_jacobian(x, u);
    py::gil_scoped_acquire gil;
    return matrix(checked(call("jacobian_state", cb_->jacobian, x, u), "jacobian_state", {3, 3}));
  }

 private:
  /// fn(x, u, dt) or, for the covariance, fn(x, u, dt, control_sd, state_sd); a Python exception
  /// becomes an InvalidArgument naming the model and the callback (raised with the GIL held).
  py::object call(const char* what, const py::object& fn, const Pose& x, const Control& u,
                  bool with_noise = false) const {
    try {
      if (with_noise)
        return fn(numpy_of(x.data(), 3), numpy_of(u.data(), 2), dt_,
                  numpy_of(control_sd_.data(), 2), numpy_of(state_sd_.data(), 3));
      return fn(numpy_of(x.data(), 3), numpy_of(u.data(), 2), dt_);
    } catch (py::error_already_set& e) {
      throw InvalidArgument(
          fmt::format("motion model '{}': {} raised {}", cb_->name, what, e.what()));
    }
  }
  Array checked(const py::object& result, const char* what, std::vector<py::ssize_t> shape) const {
    try {
      return require_shape(result, fmt::format("motion model '{}': {}", cb_->name, what),
                           std::move(shape));
    } catch (py::error_already_set& e) {  // not convertible to a float array
      throw InvalidArgument(fmt::format("motion model '{}': {} returned {}, expected numbers",
                                        cb_->name, what, type_name(result)));
    }
  }
  static Mat3 matrix(const Array& a) {
    Mat3 m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m(i, j) = a.data()[3 * i + j];
    return m;
  }
  /// Central differences of predict, for a model registered without jacobian_state.
  Mat3 differenced_jacobian(const Pose& x, const Control& u) const {
    Mat3 j;
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6 * (1.0 + std::abs(x(k)));
      Pose up = x, down = x;
      up(k) += h;
      down(k) -= h;
      j.col(k) = (predict(up, u) - predict(down, u)) / (2.0 * h);
    }
    return j;
  }

  const MotionCallbacks* cb_;
  double dt_;
  Vec<2> control_sd_;
  Vec<3> state_sd_;
};

py::object callable_arg(const py::object& o, const char* name, bool optional) {
  if (optional && o.is_none()) return o;
  if (!PyCallable_Check(o.ptr()))
    throw InvalidArgument(fmt::format("register_motion_model: expected {} to be callable, got {}",
                                      name, type_name(o)));
  return o;
}

std::vector<double> sd_arg(const py::object& o, const char* name, py::ssize_t n) {
  const Array a = require_shape(o, fmt::format("register_motion_model: {}", name), {n});
  std::vector<double> v(a.data(), a.data() + n);
  for (double x : v)
    if (!(x >= 0.0) || !std::isfinite(x))
      throw InvalidArgument(
          fmt::format("register_motion_model: expected {} of finite values >= 0, got {}", name, x));
  return v;
}

void register_python_model(const std::string& name, const py::object& predict,
                           const py::object& covariance, const py::object& jacobian,
                           const py::object& dt, const py::object& control_sd,
                           const py::object& state_sd, const std::string& controls,
                           const std::string& description) {
  auto cb = std::make_unique<MotionCallbacks>(
      MotionCallbacks{name, callable_arg(predict, "predict", false),
                      callable_arg(covariance, "process_covariance", false),
                      callable_arg(jacobian, "jacobian_state", true)});
  const MotionCallbacks* callbacks = cb.get();
  experiments::MotionModelEntry e;
  e.name = name;
  e.description = description;
  e.controls = controls;
  e.keys = {{"dt", "control period [s]",
             number_arg(dt, "register_motion_model: dt", 0.0, 60.0, /*lo_open=*/true)}};
  e.default_noise = {sd_arg(control_sd, "control_sd", 2), sd_arg(state_sd, "state_sd", 3)};
  e.build = [callbacks](const robot::VehicleDeclaration& v, const experiments::MotionNoise& noise) {
    for (const auto& parameter : v.parameters)
      require(parameter.first == "dt", "vehicle '{}': expected parameters among dt, got '{}'",
              callbacks->name, parameter.first);
    const auto& c = noise.control_sd;
    const auto& q = noise.state_sd;
    return robot::AnyMotionModel(PythonMotionModel(callbacks, *v.parameter("dt"),
                                                   Vec<2>(c[0], c[1]), Vec<3>(q[0], q[1], q[2])));
  };
  experiments::register_motion_model(std::move(e));  // refuses a taken or malformed name
  (void)cb.release();  // kept for the life of the process (see MotionCallbacks)
}

py::list motion_model_list() {
  py::list out;
  for (const auto& e : experiments::motion_models()) {
    py::dict keys;
    for (const auto& k : e.keys) keys[py::str(k.name)] = py::make_tuple(k.default_value, k.meaning);
    py::dict d;
    d["name"] = e.name;
    d["description"] = e.description;
    d["controls"] = e.controls;
    d["keys"] = keys;
    d["control_sd"] = e.default_noise.control_sd;
    d["state_sd"] = e.default_noise.state_sd;
    out.append(d);
  }
  return out;
}

}  // namespace

void init_motion_registry(py::module_& m) {
  // The defaults and the docstring are python/implicit/models.py's.
  m.def("register_motion_model", &register_python_model, py::arg("name"), py::arg("predict"),
        py::arg("process_covariance"), py::arg("jacobian_state"), py::arg("dt"),
        py::arg("control_sd"), py::arg("state_sd"), py::arg("controls"), py::arg("description"));
  m.def("motion_models", &motion_model_list);
}

}  // namespace implicit::python
