// implicit.sample, resample, ess, log_sum_exp: the sampling core driven by Python callables.
//
// F may be a plain function of one point (shape (d,)) or vectorised (shape (k, d) -> (k,)).
// Derivatives come from `grad` and `hess` when given, else from central finite differences.
// Python callbacks hold the GIL, so the sampler runs on one thread here.

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
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

/// Two minima closer than this, in standard deviations of either's Laplace approximation, are
/// one: converged Newton iterates of one minimum agree far more closely, and components this
/// close give the same mixture to within 1e-2 in log q.
constexpr double kMergeDistance = 1e-2;

/// The minima found from every start, merged, sorted by phi; and what the caller warns about.
struct Minima {
  std::vector<Laplace<Eigen::Dynamic>> modes;
  std::vector<int> found_by;    ///< for each start, its mode (-1: the minimiser failed)
  int iterations = 0;           ///< Newton iterations over all starts
  MinimizeStatus first_status;  ///< of the first start (the error message when all fail)
  int first_iterations = 0;
};

template <typename T>
Minima find_minima(const T& target, const MatX& starts, const MinimizeOptions& options) {
  Minima out;
  std::vector<int> raw;  // index into out.modes before sorting
  for (Eigen::Index k = 0; k < starts.cols(); ++k) {
    const auto r = minimize(target, VecX(starts.col(k)), options);
    out.iterations += r.iterations;
    if (k == 0) {
      out.first_status = r.status;
      out.first_iterations = r.iterations;
    }
    const auto lp =
        r.converged() ? Laplace<Eigen::Dynamic>::try_make(r.x, r.value, r.hessian) : std::nullopt;
    if (!lp || !std::isfinite(lp->phi)) {
      raw.push_back(-1);
      continue;
    }
    int same = -1;
    for (std::size_t i = 0; i < out.modes.size() && same < 0; ++i) {
      const VecX delta = lp->mu - out.modes[i].mu;
      const double da = (lp->L.transpose() * delta).norm();
      const double db = (out.modes[i].L.transpose() * delta).norm();
      if (std::max(da, db) < kMergeDistance) same = static_cast<int>(i);
    }
    if (same < 0) {
      out.modes.push_back(*lp);
      same = static_cast<int>(out.modes.size()) - 1;
    } else if (lp->phi < out.modes[same].phi) {
      out.modes[same] = *lp;  // the lower of two iterates of one minimum
    }
    raw.push_back(same);
  }
  std::vector<int> order(out.modes.size()), rank(out.modes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return out.modes[a].phi < out.modes[b].phi; });
  std::vector<Laplace<Eigen::Dynamic>> sorted;
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    sorted.push_back(out.modes[order[i]]);
  }
  out.modes = std::move(sorted);
  for (int r : raw) out.found_by.push_back(r < 0 ? -1 : rank[r]);
  return out;
}

/// The sample with the lowest F: below the lowest minimum found, it shows that F has a lower
/// minimum that no start reached.
struct LowestSample {
  double value = std::numeric_limits<double>::infinity();
  VecX x;
  void see(const VecX& at, double v) {
    if (std::isfinite(v) && v < value) {
      value = v;
      x = at;
    }
  }
};

/// Runs `draw(target)` (one F call per sample, in sample order: a serial run) with F evaluated
/// on all n samples in one call when vectorized: a first pass records the points, one call of F
/// evaluates them all, a second pass replays the values.
template <typename Draw, typename T>
SampleSet<Eigen::Dynamic> draw_batched(const PythonDensity& d, std::size_t n, bool batched,
                                       const T& target, LowestSample& lowest, Draw draw) {
  if (!batched) return draw(target);
  MatX points(d.dim, static_cast<Eigen::Index>(n));
  Eigen::Index next = 0;
  draw(make_analytic_target<Eigen::Dynamic>(
      [&](const VecX& x, VecX*, MatX*) {
        points.col(next++) = x;
        return 0.0;
      },
      d.dim));
  // points is (d, n) column-major: the same memory as a C-ordered (n, d) array.
  py::array_t<double> batch({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d.dim)},
                            points.data());
  const Array values =
      require_shape(d.f(batch), "F(x) of an (n, d) array", {static_cast<py::ssize_t>(n)}, false);
  next = 0;
  return draw(make_analytic_target<Eigen::Dynamic>(
      [&](const VecX& x, VecX*, MatX*) {
        const double v = values.data()[next++];
        lowest.see(x, v);
        return v;
      },
      d.dim));
}

/// Whether the Hessian of F at x is positive definite (F locally convex there). Not finite: no
/// verdict (true); the minimiser reports that case itself.
template <typename T>
bool locally_convex(const T& target, const VecX& x) {
  MatX h;
  const double v = target.evaluate(x, nullptr, &h);
  if (!std::isfinite(v) || !h.allFinite()) return true;
  return Laplace<Eigen::Dynamic>::try_make(x, v, h).has_value();
}

py::dict sample(const py::object& f, const py::object& x0_in, std::size_t n, const py::object& grad,
                const py::object& hess, const std::string& map, std::uint64_t seed, bool vectorized,
                const py::object& starts_in) {
  const Array x0a = require_shape(x0_in, "x0", {-1});
  PythonDensity d{f, grad, hess, vectorized, static_cast<int>(x0a.shape(0))};
  require(d.dim >= 1, "sample: x0: expected at least one coordinate, got shape (0,)");
  require(n >= 1, "sample: n: expected at least one sample, got {}", n);
  // Column 0: x0; then the rows of `starts`, if any.
  Eigen::Index k = 1;
  Array sa;
  if (!starts_in.is_none()) {
    sa = require_shape(starts_in, "starts", {-1, d.dim});
    require(sa.shape(0) >= 1, "sample: starts: expected at least one row, got shape (0, {})",
            d.dim);
    k += sa.shape(0);
  }
  MatX starts(d.dim, k);
  starts.col(0) = Eigen::Map<const VecX>(x0a.data(), d.dim);
  for (Eigen::Index i = 1; i < k; ++i)
    starts.col(i) = Eigen::Map<const VecX>(sa.data() + (i - 1) * d.dim, d.dim);
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
  const bool x0_convex = locally_convex(target, starts.col(0));
  const Minima minima = find_minima(target, starts, options.minimize);
  require(!minima.modes.empty(),
          "implicit sampling: minimising F failed with status '{}' after {} iterations{}",
          to_string(minima.first_status), minima.first_iterations,
          k > 1 ? fmt::format(" (and from all {} other starts)", k - 1) : std::string());
  require(minima.modes.size() == 1 || options.map == MapKind::kLinear,
          "sample: map: the mixture over {} minima uses the linear map, got 'random' (pass "
          "map='linear', or starts that find one minimum)",
          minima.modes.size());
  LowestSample lowest;
  auto watched = make_analytic_target<Eigen::Dynamic>(
      [&](const VecX& x, VecX* g, MatX* h) {
        const double v = full(x, g, h);
        lowest.see(x, v);
        return v;
      },
      d.dim);
  const StreamKey key{seed};
  const bool batched = vectorized && options.map == MapKind::kLinear;
  SampleSet<Eigen::Dynamic> s;
  std::vector<double> log_pi{0.0};
  if (minima.modes.size() == 1) {
    const auto& laplace = minima.modes.front();
    s = draw_batched(d, n, batched, watched, lowest,
                     [&](const auto& t) { return sample_with(t, laplace, n, key, options); });
  } else {
    const MixtureProposal<Eigen::Dynamic> q(minima.modes);
    log_pi = q.log_mixture_weights();
    s = draw_batched(d, n, batched, watched, lowest,
                     [&](const auto& t) { return sample_mixture(t, q, n, key, options); });
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
  out["status"] = std::string(to_string(MinimizeStatus::kConverged));
  out["iterations"] = minima.iterations;
  const auto& best = minima.modes.front();
  out["mode"] = adopt(VecX(best.mu), {d.dim});
  out["phi"] = best.phi;
  out["log_det_L"] = best.log_det_L;
  const auto kk = static_cast<py::ssize_t>(minima.modes.size());
  MatX mus(d.dim, kk);
  std::vector<double> phis, pis;
  for (py::ssize_t i = 0; i < kk; ++i) {
    mus.col(i) = minima.modes[i].mu;
    phis.push_back(minima.modes[i].phi);
    pis.push_back(std::exp(log_pi[i]));
  }
  out["minima"] = adopt(std::move(mus), {kk, static_cast<py::ssize_t>(d.dim)});
  out["minima_phi"] = adopt_vector(std::move(phis));
  out["mixture_weights"] = adopt_vector(std::move(pis));
  out["found_by"] = minima.found_by;
  out["x0_convex"] = x0_convex;
  out["lowest_sample_F"] = lowest.value;
  out["lowest_sample"] =
      lowest.x.size() == d.dim ? py::object(adopt(VecX(lowest.x), {d.dim})) : py::none();
  return out;
}

std::vector<double> as_vector(const py::object& o, const std::string& name) {
  const Array a = require_shape(o, name, {-1});
  return {a.data(), a.data() + a.shape(0)};
}

}  // namespace

void init_core(py::module_& m) {
  m.def("_sample", &sample, py::arg("F"), py::arg("x0"), py::arg("n"), py::arg("grad"),
        py::arg("hess"), py::arg("map"), py::arg("seed"), py::arg("vectorized"), py::arg("starts"));
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
