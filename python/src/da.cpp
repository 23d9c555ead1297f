// implicit.da: the data-assimilation benchmarks of `implicit da` (experiments/da.hpp) and the
// Lorenz models they run on (implicit/da/lorenz.hpp). run() calls the tool's own runner with the
// tool's settings struct, so its dict is the tool's --json, number for number; every setting is
// checked against the range of its flag (apps/cmd_da.cpp) before anything runs.

#include <pybind11/stl.h>

#include <exception>
#include <limits>
#include <memory>
#include <string_view>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "common.hpp"
#include "experiments/choices.hpp"
#include "experiments/da.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/da/lorenz.hpp"
#include "run_settings.hpp"

namespace implicit::python {
namespace {

/// One numeric setting of run(): the keyword, the flag of `implicit da` and the range of its
/// check in apps/cmd_da.cpp (tests/test_da.py compares them with `implicit da --help`).
struct DaRange {
  const char* key;
  const char* flag;
  double lo;
  double hi;
  bool integer;
};

constexpr DaRange kDaRanges[] = {
    {"dim", "--dim", 4, 100000, true},
    {"forcing", "--forcing", -1e6, 1e6, false},
    {"members", "--members", 2, 10000000, true},
    {"seeds", "--seeds", 1, 100000, true},
    {"jitter", "--jitter", 0.0, 1e6, false},
    {"inflation", "--inflation", 1.0, 1e3, false},
    {"resample_threshold", "--resample-threshold", 0.0, 1.0, false},
    {"lag", "--lag", 1, 1000, true},
    {"starts", "--starts", 1, 1000, true},
    {"bandwidth", "--bandwidth", 0.0, 1.0, false},
    {"obs_every", "--obs-every", 1, 10000, true},
    {"model_noise", "--model-noise", 0.0, 1e6, false},
    {"cycles", "--cycles", 0, 100000000, true},
    {"threads", "--threads", 0, 1024, true},
};

const DaRange& da_range(const char* key) {
  for (const DaRange& r : kDaRanges)
    if (std::string_view(r.key) == key) return r;
  throw InvalidArgument(fmt::format("da: no range for the setting '{}'", key));
}

py::object da_setting(const py::dict& kw, const char* key) {
  require(kw.contains(key), "da.run: missing setting '{}'", key);
  return kw[key];
}

double da_number(const py::dict& kw, const char* key) {
  const DaRange& r = da_range(key);
  return number_arg(da_setting(kw, key), key, r.lo, r.hi);
}

int da_int(const py::dict& kw, const char* key) {
  const DaRange& r = da_range(key);
  return static_cast<int>(int_arg(da_setting(kw, key), key, static_cast<long long>(r.lo),
                                  static_cast<long long>(r.hi)));
}

experiments::DaSettings da_settings(const py::dict& kw) {
  experiments::DaSettings s;
  s.model = choice_arg(da_setting(kw, "model"), "model", {"lorenz63", "lorenz96"});
  s.dim = da_int(kw, "dim");
  s.forcing = da_number(kw, "forcing");
  s.method = choice_arg(da_setting(kw, "method"), "method", experiments::da_methods().names());
  s.members = da_int(kw, "members");
  s.seeds = da_int(kw, "seeds");
  s.jitter = da_number(kw, "jitter");
  s.regularisation = choice_arg(da_setting(kw, "regularisation"), "regularisation", {"iso", "cov"});
  s.inflation = da_number(kw, "inflation");
  s.resample_threshold = da_number(kw, "resample_threshold");
  s.map = choice_arg(da_setting(kw, "map"), "map", {"linear", "random"});
  // None: the smoother's default window (the tool without --lag); the runner refuses a lag
  // with the filters, as the tool does.
  s.lag = da_setting(kw, "lag").is_none() ? 0 : da_int(kw, "lag");
  s.starts = da_setting(kw, "starts").is_none() ? 0 : da_int(kw, "starts");
  s.bandwidth = da_number(kw, "bandwidth");
  s.obs_every = da_int(kw, "obs_every");
  s.model_noise = da_number(kw, "model_noise");
  s.cycles = da_int(kw, "cycles");
  return s;
}

std::string run_da(const py::dict& kw, const py::object& seed, const py::object& threads,
                   const py::object& progress) {
  // Checked in the order of the signature's keywords, then seed, threads and progress.
  const experiments::DaSettings s = da_settings(kw);
  // seed and threads as the tool's --seed and --threads (run_settings.cpp); no CSV files.
  experiments::RunContext ctx = run_context(seed, py::none(), threads);
  return with_python_progress(ctx, progress, [&] {
    py::gil_scoped_release unlocked;
    ThreadLimit limit(ctx.threads);
    return experiments::run_da(s, ctx).dump();
  });
}

// ---- the models ------------------------------------------------------------------------------

constexpr long long kDaMaxSteps = std::numeric_limits<int>::max();

/// A row-major copy of an Eigen matrix (numpy's default layout).
py::array_t<double> da_matrix(const Eigen::MatrixXd& m) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const auto rows = static_cast<py::ssize_t>(m.rows()), cols = static_cast<py::ssize_t>(m.cols());
  return adopt(RowMajor(m), {rows, cols});
}

py::array_t<double> da_vector(const Eigen::VectorXd& v) {
  return adopt(Eigen::VectorXd(v), {static_cast<py::ssize_t>(v.size())});
}

Eigen::VectorXd da_state(const py::object& x, int n) {
  const Array a = require_shape(x, "x", {n});
  return Eigen::Map<const Eigen::VectorXd>(a.data(), n);
}

struct DaStepArgs {
  double dt;
  int k;
  bool jacobian;
};

DaStepArgs da_step_args(const py::object& dt, const py::object& k, const py::object& jacobian) {
  return {number_arg(dt, "dt", 0.0, kUnbounded, /*lo_open=*/true),
          static_cast<int>(int_arg(k, "k", 0, kDaMaxSteps)), bool_arg(jacobian, "jacobian")};
}

py::object da_steps_result(const Eigen::VectorXd& x, const Eigen::MatrixXd* jacobian) {
  if (jacobian == nullptr) return da_vector(x);
  return py::make_tuple(da_vector(x), da_matrix(*jacobian));
}

py::object lorenz63_steps(const da::Lorenz63& l, const py::object& x0, const py::object& dt,
                          const py::object& k, const py::object& jacobian) {
  Vec<3> x = da_state(x0, 3);
  const DaStepArgs a = da_step_args(dt, k, jacobian);
  Mat<3> j;
  {
    py::gil_scoped_release unlocked;
    l.steps(x, a.dt, a.k, a.jacobian ? &j : nullptr);
  }
  const Eigen::MatrixXd jd = j;
  return da_steps_result(x, a.jacobian ? &jd : nullptr);
}

py::object lorenz96_steps(const da::Lorenz96& l, const py::object& x0, const py::object& dt,
                          const py::object& k, const py::object& jacobian) {
  Eigen::VectorXd x = da_state(x0, l.dim());
  const DaStepArgs a = da_step_args(dt, k, jacobian);
  Eigen::MatrixXd j;
  {
    py::gil_scoped_release unlocked;
    da::Lorenz96::Workspace w(l.dim());
    l.steps(x, a.dt, a.k, w, a.jacobian ? &j : nullptr);
  }
  return da_steps_result(x, a.jacobian ? &j : nullptr);
}

void bind_lorenz(py::module_& m) {
  py::class_<da::Lorenz63>(m, "Lorenz63",
                           "Lorenz-63: dx/dt = (sigma (y - x), x (rho - z) - y, x y - beta z).")
      .def(py::init([](const py::object& sigma, const py::object& rho, const py::object& beta) {
             return da::Lorenz63{number_arg(sigma, "sigma", -kUnbounded, kUnbounded),
                                 number_arg(rho, "rho", -kUnbounded, kUnbounded),
                                 number_arg(beta, "beta", -kUnbounded, kUnbounded)};
           }),
           py::arg("sigma") = 10.0, py::arg("rho") = 28.0, py::arg("beta") = 8.0 / 3.0)
      .def_property_readonly("sigma", [](const da::Lorenz63& l) { return l.sigma; })
      .def_property_readonly("rho", [](const da::Lorenz63& l) { return l.rho; })
      .def_property_readonly("beta", [](const da::Lorenz63& l) { return l.beta; })
      .def_property_readonly("dim", [](const da::Lorenz63&) { return 3; })
      .def(
          "tendency",
          [](const da::Lorenz63& l, const py::object& x) {
            return da_vector(l.tendency(da_state(x, 3)));
          },
          py::arg("x"), "dx/dt at x (3,).")
      .def("steps", &lorenz63_steps, py::arg("x"), py::arg("dt"), py::arg("k"),
           py::arg("jacobian") = false,
           "The state after k RK4 steps of length dt from x; with jacobian=True, (state, the "
           "derivative of the k-step map at x).");

  py::class_<da::Lorenz96>(m, "Lorenz96",
                           "Lorenz-96: dx_i/dt = (x_{i+1} - x_{i-2}) x_{i-1} - x_i + F, cyclic.")
      .def(py::init([](const py::object& n, const py::object& forcing) {
             const DaRange& r = da_range("dim");
             return da::Lorenz96(static_cast<int>(int_arg(n, "n", static_cast<long long>(r.lo),
                                                          static_cast<long long>(r.hi))),
                                 number_arg(forcing, "forcing", -kUnbounded, kUnbounded));
           }),
           py::arg("n"), py::arg("forcing") = 8.0)
      .def_property_readonly("n", &da::Lorenz96::dim)
      .def_property_readonly("dim", &da::Lorenz96::dim)
      .def_property_readonly("forcing", &da::Lorenz96::forcing)
      .def(
          "tendency",
          [](const da::Lorenz96& l, const py::object& x) {
            Eigen::VectorXd out(l.dim());
            l.tendency(da_state(x, l.dim()), out);
            return da_vector(out);
          },
          py::arg("x"), "dx/dt at x (n,).")
      .def("steps", &lorenz96_steps, py::arg("x"), py::arg("dt"), py::arg("k"),
           py::arg("jacobian") = false,
           "The state after k RK4 steps of length dt from x; with jacobian=True, (state, the "
           "derivative of the k-step map at x).");
}

}  // namespace

void init_da(py::module_& m) {
  bind_lorenz(m);
  m.def("_run", &run_da, py::arg("settings"), py::arg("seed"), py::arg("threads"),
        py::arg("progress") = py::none(),
        "The run of `implicit da` with these settings, as its --json text (use implicit.da.run).");
  m.def(
      "_setting_ranges",
      [] {
        py::list out;
        for (const DaRange& r : kDaRanges)
          out.append(py::dict(py::arg("key") = r.key, py::arg("flag") = r.flag,
                              py::arg("lo") = r.lo, py::arg("hi") = r.hi,
                              py::arg("integer") = r.integer));
        return out;
      },
      "The numeric ranges of implicit.da.run: key, the tool's flag, lo, hi, integer.");
}

}  // namespace implicit::python
