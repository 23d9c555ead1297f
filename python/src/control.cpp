// implicit.control: the double slit and Himmelblau control estimates at one state, with the
// estimator choice (paper §3, spec §2.4-2.6). The closed-loop studies are in runs.cpp.

#include <pybind11/stl.h>

#include <limits>

#include "common.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/control/himmelblau.hpp"

namespace implicit::python {
namespace {

constexpr long long kIntMin = std::numeric_limits<int>::min();
constexpr long long kIntMax = std::numeric_limits<int>::max();

control::SlitEstimator parse_estimator(const std::string& name) {
  if (name == "paper") return control::SlitEstimator::kPaper;
  if (name == "corrected") return control::SlitEstimator::kFrozenWall;
  if (name == "plain") return control::SlitEstimator::kPlainFd;
  throw InvalidArgument(fmt::format(
      "estimate_control: estimator: expected 'paper', 'corrected' or 'plain', got '{}'", name));
}

void bind_slit(py::module_& m) {
  py::class_<control::DoubleSlit>(m, "DoubleSlit", R"doc(
The double slit problem (paper §3.1, Table 1; spec §2.4): dx = u dt + sqrt(sigma) dW, a wall at
t1 with slits [-6, -4] and [6, 8], final cost x^2 / 2, control cost r u^2 / 2.

DoubleSlit(final_time=2.0, wall_time=1.0, sigma=1.0, control_cost=0.1, dt=0.02)

estimate_control(x, k, samples, estimator="corrected", seed=1, step=0) estimates the control at
state x and grid step k (t = k dt) from `samples` reference samples per slit: estimator "paper"
(the paper's: dominant slit, no weights; biased), "corrected" (both slits, exact weights, frozen
wall) or "plain" (both slits, plain finite differences). Returns a dict with u, log_psi, ess,
samples, passed, fallback. exact_control(x, t) and exact_log_psi(x, t) are the closed forms.

Example: ``implicit.control.DoubleSlit().estimate_control(1.0, 0, 50)["u"]``)doc")
      .def(py::init([](double final_time, double wall_time, double sigma, double control_cost,
                       double dt) {
             control::DoubleSlitParameters p;
             p.final_time = final_time;
             p.wall_time = wall_time;
             p.sigma = sigma;
             p.control_cost = control_cost;
             p.dt = dt;
             return control::DoubleSlit(p);
           }),
           py::arg("final_time") = 2.0, py::arg("wall_time") = 1.0, py::arg("sigma") = 1.0,
           py::arg("control_cost") = 0.1, py::arg("dt") = 0.02)
      .def_property_readonly("num_steps", &control::DoubleSlit::num_steps)
      .def_property_readonly("wall_step", &control::DoubleSlit::wall_step)
      .def("exact_control", &control::DoubleSlit::exact_control, py::arg("x"), py::arg("t"))
      .def("exact_log_psi", &control::DoubleSlit::exact_log_psi, py::arg("x"), py::arg("t"))
      .def(
          "estimate_control",
          [](const control::DoubleSlit& s, const py::object& x, const py::object& k,
             const py::object& samples, const py::object& estimator, const py::object& seed,
             const py::object& step) {
            // The grid step and the sample count are checked by the estimator (its ranges
            // depend on the problem); here only that they are integers, never truncated.
            const double xv = number_arg(x, "x", -kUnbounded, kUnbounded);
            const auto kv = static_cast<int>(int_arg(k, "k", kIntMin, kIntMax));
            const auto m = static_cast<int>(int_arg(samples, "samples", kIntMin, kIntMax));
            require(py::isinstance<py::str>(estimator), "estimator: expected a str, got {}",
                    type_name(estimator));
            const auto name = estimator.cast<std::string>();
            const auto e =
                s.estimate_control(xv, kv, m, parse_estimator(name),
                                   StreamKey{seed_arg(seed, "seed"), seed_arg(step, "step"), 0, 0});
            py::dict d;
            d["u"] = e.u;
            d["log_psi"] = e.log_psi;
            d["ess"] = e.ess;
            d["samples"] = e.samples;
            d["passed"] = e.passed;
            d["fallback"] = e.fallback;
            return d;
          },
          py::arg("x"), py::arg("k"), py::arg("samples") = 50, py::arg("estimator") = "corrected",
          py::arg("seed") = 1, py::arg("step") = 0);
}

void bind_himmelblau(py::module_& m) {
  m.def(
      "himmelblau_control",
      [](const py::object& x_in, const py::object& k_in, const py::object& samples_in,
         const py::object& seed_in, const py::object& step_in, double control_cost, double sigma,
         double dt, double final_time) {
        control::HimmelblauProblem pb;
        pb.control_cost = control_cost;
        pb.sigma = sigma;
        pb.dt = dt;
        pb.final_time = final_time;
        pb.validate();
        // Integers, never truncated; their ranges are the problem's (himmelblau_control).
        const auto k = static_cast<int>(int_arg(k_in, "k", kIntMin, kIntMax));
        const auto samples = static_cast<int>(int_arg(samples_in, "samples", kIntMin, kIntMax));
        const std::uint64_t seed = seed_arg(seed_in, "seed");
        const std::uint64_t step = seed_arg(step_in, "step");
        const Array xa = require_shape(x_in, "x", {2});
        const Vec<2> x(xa.data()[0], xa.data()[1]);
        const auto e = control::himmelblau_control(pb, x, k, samples, x, {seed, step, 0, 0});
        py::dict d;
        d["u"] = py::array_t<double>(2, e.u.data());
        d["laplace_u"] = py::array_t<double>(2, e.laplace_u.data());
        d["log_psi"] = e.log_psi;
        d["ess"] = e.ess;
        d["end"] = py::array_t<double>(2, e.end.data());
        d["status"] = std::string(to_string(e.status));
        return d;
      },
      py::arg("x"), py::arg("k") = 0, py::arg("samples") = 50, py::arg("seed") = 1,
      py::arg("step") = 0, py::arg("control_cost") = 0.01, py::arg("sigma") = 0.01,
      py::arg("dt") = 1.0, py::arg("final_time") = 20.0,
      R"doc(
One control estimate of the Himmelblau problem (paper §3.3, spec §2.6) at state x (2,) and grid
step k, with `samples` implicit samples (linear map) and finite differences with common random
numbers. Returns a dict with u (2,), laplace_u (2,), log_psi, ess, end (2,) (the minimiser of the
end point) and the minimisation status.

Example: ``implicit.control.himmelblau_control([-1.0, -4.0], 0, 50, seed=3)["u"]``)doc");
}

}  // namespace

void init_control(py::module_& m) {
  bind_slit(m);
  bind_himmelblau(m);
}

}  // namespace implicit::python
