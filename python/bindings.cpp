// Python bindings of the implicit sampling core.
//
//   import implicit_py as ip
//   F = lambda x: 0.5 * x @ x + 0.25 * (x**4).sum()
//   s = ip.sample(F, x0=[1.0, 1.0], samples=10000, seed=1, map="random")
//   s["log_Z"], s["ess"], s["x"], s["weights"]
//
// Derivatives of a Python F are taken by central finite differences unless `grad` and `hess`
// callables are given. Python callbacks hold the GIL, so sampling runs on one thread here.

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "implicit/implicit.hpp"

namespace py = pybind11;
using implicit::Mat;
using implicit::Vec;
using VecX = Vec<Eigen::Dynamic>;
using MatX = Mat<Eigen::Dynamic>;

namespace {

py::dict sample(const std::function<double(const VecX&)>& f,
                const std::optional<std::function<VecX(const VecX&)>>& grad,
                const std::optional<std::function<MatX(const VecX&)>>& hess, const VecX& x0,
                std::size_t samples, std::uint64_t seed, const std::string& map) {
  auto numeric = implicit::make_numeric_target<Eigen::Dynamic>(f, static_cast<int>(x0.size()));
  auto target = implicit::make_analytic_target<Eigen::Dynamic>(
      [&](const VecX& x, VecX* g, MatX* h) {
        VecX gn;
        MatX hn;
        const bool need_numeric = (g && !grad) || (h && !hess);
        const double v = need_numeric ? numeric.evaluate(x, (g && !grad) ? &gn : nullptr,
                                                         (h && !hess) ? &hn : nullptr)
                                      : f(x);
        if (g) *g = grad ? (*grad)(x) : gn;
        if (h) *h = hess ? (*hess)(x) : hn;
        return v;
      },
      static_cast<int>(x0.size()));
  implicit::SamplerOptions options;
  options.parallel = false;
  if (map == "random")
    options.map = implicit::MapKind::kRandom;
  else if (map != "linear")
    throw implicit::InvalidArgument("map: expected 'linear' or 'random', got '" + map + "'");
  const auto s = implicit::sample(target, x0, samples, {seed}, options);
  py::dict d;
  d["x"] = MatX(s.x.transpose());
  d["log_weights"] = s.log_weights;
  d["weights"] = s.weights;
  d["log_Z"] = s.log_Z;
  d["ess"] = s.ess;
  d["mode"] = VecX(s.modes.front().mu);
  d["phi"] = s.modes.front().phi;
  d["log_det_L"] = s.modes.front().log_det_L;
  return d;
}

}  // namespace

PYBIND11_MODULE(implicit_py, m) {
  m.doc() = "implicit: implicit sampling core (linear and random maps, weights, resampling)";
  py::register_exception<implicit::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);
  m.def("sample", &sample, py::arg("F"), py::arg("grad") = py::none(), py::arg("hess") = py::none(),
        py::arg("x0"), py::arg("samples") = 1000, py::arg("seed") = 1, py::arg("map") = "linear",
        "Minimise F (a negative log density) from x0 and draw weighted samples.");
  m.def("log_sum_exp", [](const std::vector<double>& a) { return implicit::log_sum_exp(a); });
  m.def("effective_sample_size",
        [](const std::vector<double>& w) { return implicit::effective_sample_size(w); });
  m.def(
      "resample",
      [](const std::string& scheme, const std::vector<double>& w, const std::vector<double>& u,
         std::size_t n) {
        return implicit::resample(implicit::parse_resampling_scheme(scheme), w, u, n);
      },
      py::arg("scheme"), py::arg("weights"), py::arg("uniforms"), py::arg("n"));
  m.attr("__version__") = implicit::version();
}
