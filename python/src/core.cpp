// implicit.sample, resample, ess, log_sum_exp: the sampling core driven by Python callables.
//
// F may be a plain function of one point (shape (d,)) or vectorised (shape (k, d) -> (k,)).
// Derivatives come from `grad` and `hess` when given, else from central finite differences.
// Python callbacks hold the GIL, so the sampler runs on one thread here.

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>

#include "common.hpp"
#include "implicit/implicit.hpp"

namespace implicit::python {
namespace {

using VecX = Vec<Eigen::Dynamic>;
using MatX = Mat<Eigen::Dynamic>;

/// A Python F (and optional derivatives) as the value/gradient/Hessian callback of a target.
struct PythonDensity {
  py::object f, grad, hess;
  bool vectorized = false;
  int dim = 0;

  double value(const VecX& x) const {
    py::array_t<double> a(vectorized ? std::vector<py::ssize_t>{1, dim}
                                     : std::vector<py::ssize_t>{dim});
    std::copy(x.data(), x.data() + dim, a.mutable_data());
    const Array r = require_shape(
        f(a), "F(x)", vectorized ? std::vector<py::ssize_t>{1} : std::vector<py::ssize_t>{}, false);
    return r.data()[0];
  }
  VecX gradient(const VecX& x) const {
    const Array g = require_shape(grad(py::array_t<double>(dim, x.data())), "grad(x)", {dim});
    return Eigen::Map<const VecX>(g.data(), dim);
  }
  MatX hessian(const VecX& x) const {
    const Array h = require_shape(hess(py::array_t<double>(dim, x.data())), "hess(x)", {dim, dim});
    // Row-major numpy and column-major Eigen agree for a symmetric matrix; symmetrised anyway.
    const Eigen::Map<const MatX> m(h.data(), dim, dim);
    return 0.5 * (m + m.transpose());
  }
};

implicit::MapKind parse_map(const std::string& map) {
  if (map == "random") return implicit::MapKind::kRandom;
  require(map == "linear", "sample: map: expected 'linear' or 'random', got '{}'", map);
  return implicit::MapKind::kLinear;
}

py::dict sample(const py::object& f, const py::object& x0_in, std::size_t n, const py::object& grad,
                const py::object& hess, const std::string& map, std::uint64_t seed,
                bool vectorized) {
  const Array x0a = require_shape(x0_in, "x0", {-1});
  PythonDensity d{f, grad, hess, vectorized, static_cast<int>(x0a.shape(0))};
  require(d.dim >= 1, "sample: x0: expected at least one coordinate, got shape (0,)");
  require(n >= 1, "sample: n: expected at least one sample, got {}", n);
  const VecX x0 = Eigen::Map<const VecX>(x0a.data(), d.dim);
  SamplerOptions options;
  options.parallel = false;
  options.map = parse_map(map);

  auto numeric =
      make_numeric_target<Eigen::Dynamic>([&](const VecX& x) { return d.value(x); }, d.dim);
  auto full = [&](const VecX& x, VecX* g, MatX* h) {
    VecX gn;
    MatX hn;
    const bool need_numeric = (g && grad.is_none()) || (h && hess.is_none());
    const double v = need_numeric ? numeric.evaluate(x, (g && grad.is_none()) ? &gn : nullptr,
                                                     (h && hess.is_none()) ? &hn : nullptr)
                                  : d.value(x);
    if (g) *g = grad.is_none() ? gn : d.gradient(x);
    if (h) *h = hess.is_none() ? hn : d.hessian(x);
    return v;
  };
  auto target = make_analytic_target<Eigen::Dynamic>(full, d.dim);
  const auto r = minimize(target, x0, options.minimize);
  require(r.status == MinimizeStatus::kConverged,
          "implicit sampling: minimising F failed with status '{}' after {} iterations",
          to_string(r.status), r.iterations);
  const auto laplace = Laplace<Eigen::Dynamic>::make(r.x, r.value, r.hessian);
  const StreamKey key{seed};
  SampleSet<Eigen::Dynamic> s;
  if (vectorized && options.map == MapKind::kLinear) {
    // The linear map asks for F once per sample, in sample order (serial run): a first pass
    // records the points, one call of F evaluates them all, a second pass replays the values.
    MatX points(d.dim, static_cast<Eigen::Index>(n));
    Eigen::Index next = 0;
    auto record = make_analytic_target<Eigen::Dynamic>(
        [&](const VecX& x, VecX*, MatX*) {
          points.col(next++) = x;
          return 0.0;
        },
        d.dim);
    sample_with(record, laplace, n, key, options);
    // points is (d, n) column-major: the same memory as a C-ordered (n, d) array.
    py::array_t<double> batch({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d.dim)},
                              points.data());
    const Array values =
        require_shape(f(batch), "F(x) of an (n, d) array", {static_cast<py::ssize_t>(n)}, false);
    next = 0;
    auto replay = make_analytic_target<Eigen::Dynamic>(
        [&](const VecX&, VecX*, MatX*) { return values.data()[next++]; }, d.dim);
    s = sample_with(replay, laplace, n, key, options);
  } else {
    s = sample_with(target, laplace, n, key, options);
  }
  py::dict out;
  const auto m = static_cast<py::ssize_t>(s.x.cols());
  out["x"] = adopt(std::move(s.x), {m, static_cast<py::ssize_t>(d.dim)});
  out["log_weights"] = adopt_vector(std::move(s.log_weights));
  out["weights"] = adopt_vector(std::move(s.weights));
  out["log_Z"] = s.log_Z;
  out["ess"] = s.ess;
  out["zero_weight"] = s.zero_weight;
  out["map_failures"] = s.map_failures;
  out["status"] = std::string(to_string(r.status));
  out["iterations"] = r.iterations;
  out["mode"] = adopt(VecX(laplace.mu), {d.dim});
  out["phi"] = laplace.phi;
  out["log_det_L"] = laplace.log_det_L;
  return out;
}

std::vector<double> as_vector(const py::object& o, const std::string& name) {
  const Array a = require_shape(o, name, {-1});
  return {a.data(), a.data() + a.shape(0)};
}

}  // namespace

void init_core(py::module_& m) {
  m.def("_sample", &sample, py::arg("F"), py::arg("x0"), py::arg("n"), py::arg("grad"),
        py::arg("hess"), py::arg("map"), py::arg("seed"), py::arg("vectorized"));
  m.def(
      "_log_sum_exp",
      [](const py::object& a) {
        const Array v = require_shape(a, "a", {-1}, false);
        return log_sum_exp(std::span<const double>(v.data(), v.shape(0)));
      },
      py::arg("a"));
  m.def(
      "_ess", [](const py::object& w) { return effective_sample_size(as_vector(w, "weights")); },
      py::arg("weights"));
  m.def(
      "_resample",
      [](const std::string& scheme, const py::object& w, std::size_t n, std::uint64_t seed,
         const py::object& uniforms) {
        const ResamplingScheme s = parse_resampling_scheme(scheme);
        const std::vector<double> weights = as_vector(w, "weights");
        std::vector<double> u;
        if (uniforms.is_none()) {
          Rng rng({seed, 0, 0, purpose::kResampling});
          u.resize(uniforms_needed(s, n));
          for (double& x : u) x = rng.uniform();
        } else {
          u = as_vector(uniforms, "uniforms");
        }
        const std::vector<std::size_t> idx = resample(s, weights, u, n);
        py::array_t<std::int64_t> out(static_cast<py::ssize_t>(idx.size()));
        std::copy(idx.begin(), idx.end(), out.mutable_data());
        return out;
      },
      py::arg("scheme"), py::arg("weights"), py::arg("n"), py::arg("seed"), py::arg("uniforms"));
  m.def("_uniforms_needed", [](const std::string& scheme, std::size_t n) {
    return uniforms_needed(parse_resampling_scheme(scheme), n);
  });
}

}  // namespace implicit::python
