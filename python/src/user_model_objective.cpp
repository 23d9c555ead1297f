// The Python callbacks of a user's state-space model: calling them on all particles at once and
// checking what they return (shape, NaN, +inf) with messages that name the callback and the step;
// F = -log p(y | x) - log p(x | x') and its derivatives, from the user's gradient and Hessian or
// by central differences evaluated in one stacked call.

#include "user_model_callbacks.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace implicit::python::ssm {

py::array_t<double> to_numpy(const RowMatrix& m) {
  return py::array_t<double>({m.rows(), m.cols()}, m.data());
}

std::string Callbacks::where(const char* name) const {
  return fmt::format("{} at step {}", name, step);
}

RowMatrix Callbacks::points(const py::object& result, const char* name, Eigen::Index k) const {
  const std::string at = where(name);
  const Array a = require_shape(result, at, {k, dim}, false);
  const Eigen::Map<const RowMatrix> m(a.data(), k, dim);
  for (Eigen::Index r = 0; r < k; ++r)
    require(m.row(r).allFinite(), "{}: expected finite values, got a non-finite value in row {}",
            at, r);
  return m;
}

VecX Callbacks::log_densities(const py::object& result, const char* name, Eigen::Index k,
                              bool allow_minus_inf) const {
  const std::string at = where(name);
  const Array a = require_shape(result, at, {k}, false);
  VecX v = Eigen::Map<const VecX>(a.data(), k);
  for (Eigen::Index r = 0; r < k; ++r) {
    const bool ok = std::isfinite(v[r]) ||
                    (allow_minus_inf && v[r] == -std::numeric_limits<double>::infinity());
    require(ok, "{}: expected {}, got {} in row {}", at,
            allow_minus_inf ? "log densities (numbers or -inf)" : "finite log densities", v[r], r);
  }
  return v;
}

RowMatrix Callbacks::sample_initial(const RowMatrix& z) const {
  return points(initial(to_numpy(z)), "initial", z.rows());
}

RowMatrix Callbacks::sample_transition(const RowMatrix& x_prev, const RowMatrix& z) const {
  return points(transition(step, to_numpy(x_prev), to_numpy(z)), "transition", z.rows());
}

VecX Callbacks::observation(const RowMatrix& x) const {
  return log_densities(observation_logpdf(step, to_numpy(x), y), "observation_logpdf", x.rows(),
                       true);
}

VecX Callbacks::transition_density(const RowMatrix& x, const RowMatrix& x_prev) const {
  return log_densities(transition_logpdf(step, to_numpy(x), to_numpy(x_prev)), "transition_logpdf",
                       x.rows(), true);
}

std::pair<RowMatrix, VecX> Callbacks::guided(const RowMatrix& x_prev, const RowMatrix& z) const {
  const py::object r = proposal(step, to_numpy(x_prev), y, to_numpy(z));
  require(py::isinstance<py::tuple>(r) && py::len(r) == 2,
          "{}: expected a tuple (x, log_q), got {}", where("proposal"), type_name(r));
  const auto t = r.cast<py::tuple>();
  RowMatrix x = points(t[0], "proposal (x)", z.rows());
  VecX log_q = log_densities(t[1], "proposal (log_q)", z.rows(), false);
  return {std::move(x), std::move(log_q)};
}

VecX Callbacks::objective(const RowMatrix& x, const RowMatrix& x_prev) const {
  const VecX lt = transition_density(x, x_prev);
  const VecX lo = observation(x);
  VecX f(x.rows());
  for (Eigen::Index r = 0; r < x.rows(); ++r)  // -(-inf) is +inf: outside the support
    f[r] = -(lt[r] + lo[r]);
  return f;
}

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

/// Difference steps h_i = c max(1, |x_i|), rounded so that x + h is exact.
VecX steps(const Eigen::Ref<const VecX>& x, double c) {
  VecX h(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double hi = c * std::max(1.0, std::abs(x[i]));
    h[i] = (x[i] + hi) - x[i];
  }
  return h;
}

/// x_prev's rows for each stacked point: `m` copies of each row.
RowMatrix repeat_rows(const RowMatrix& a, Eigen::Index m) {
  RowMatrix out(a.rows() * m, a.cols());
  for (Eigen::Index r = 0; r < a.rows(); ++r)
    for (Eigen::Index k = 0; k < m; ++k) out.row(r * m + k) = a.row(r);
  return out;
}

}  // namespace

void PythonObjective::evaluate(const std::vector<std::size_t>& owner, const RowMatrix& x,
                               Derivatives derivatives, Evaluation& out) {
  const Eigen::Index k = x.rows(), d = x.cols();
  RowMatrix xp(k, d);
  for (Eigen::Index r = 0; r < k; ++r) xp.row(r) = x_prev.row(static_cast<Eigen::Index>(owner[r]));
  ++calls;
  if (derivatives == Derivatives::kNone) {
    out.value = cb.objective(x, xp);
    return;
  }
  const bool hessian = derivatives == Derivatives::kHessian;
  const bool has_grad = !cb.gradient.is_none(), has_hess = hessian && !cb.hessian.is_none();
  out.gradient.resize(k, d);  // sized first: hessian_at() reads d from it
  out.hessian.setZero(hessian ? k : 0, d * d);
  if (has_grad) {
    out.value = cb.objective(x, xp);
    out.gradient = user_gradient(x, xp, out.value);
  } else {
    values_differenced(x, xp, out, hessian && !has_hess);
  }
  if (has_hess)
    user_hessian(x, xp, out);
  else if (hessian && has_grad)
    gradient_differenced(x, xp, out);
}

RowMatrix PythonObjective::user_gradient(const RowMatrix& x, const RowMatrix& xp,
                                         const VecX& value) const {
  const std::string at = cb.where("gradient");
  const Array a = require_shape(cb.gradient(cb.step, to_numpy(x), to_numpy(xp), cb.y), at,
                                {x.rows(), x.cols()}, false);
  RowMatrix g = Eigen::Map<const RowMatrix>(a.data(), x.rows(), x.cols());
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    require(!std::isfinite(value[r]) || g.row(r).allFinite(),
            "{}: expected finite values where F is finite, got a non-finite value in row {}", at,
            r);
  return g;
}

void PythonObjective::user_hessian(const RowMatrix& x, const RowMatrix& xp, Evaluation& out) const {
  const std::string at = cb.where("hessian");
  const Eigen::Index k = x.rows(), d = x.cols();
  const Array a =
      require_shape(cb.hessian(cb.step, to_numpy(x), to_numpy(xp), cb.y), at, {k, d, d}, false);
  for (Eigen::Index r = 0; r < k; ++r) {
    const Eigen::Map<const RowMatrix> h(a.data() + r * d * d, d, d);
    require(!std::isfinite(out.value[r]) || h.allFinite(),
            "{}: expected finite values where F is finite, got a non-finite value in row {}", at,
            r);
    out.hessian_at(r) = 0.5 * (h + h.transpose());
  }
}

void PythonObjective::gradient_differenced(const RowMatrix& x, const RowMatrix& xp,
                                           Evaluation& out) const {
  // Central differences of the gradient: 2d stacked points per row, one call.
  const Eigen::Index k = x.rows(), d = x.cols(), m = 2 * d;
  RowMatrix pts(k * m, d);
  RowMatrix h(k, d);
  for (Eigen::Index r = 0; r < k; ++r) {
    h.row(r) = steps(x.row(r).transpose(), std::cbrt(kEps)).transpose();
    for (Eigen::Index i = 0; i < d; ++i) {
      pts.row(r * m + 2 * i) = x.row(r);
      pts(r * m + 2 * i, i) += h(r, i);
      pts.row(r * m + 2 * i + 1) = x.row(r);
      pts(r * m + 2 * i + 1, i) -= h(r, i);
    }
  }
  const RowMatrix xps = repeat_rows(xp, m);
  const VecX f = cb.objective(pts, xps);
  const RowMatrix g = user_gradient(pts, xps, f);
  for (Eigen::Index r = 0; r < k; ++r) {
    MatX hr(d, d);
    for (Eigen::Index i = 0; i < d; ++i)
      hr.col(i) = (g.row(r * m + 2 * i) - g.row(r * m + 2 * i + 1)).transpose() / (2.0 * h(r, i));
    out.hessian_at(r) = 0.5 * (hr + hr.transpose());
  }
}

void PythonObjective::values_differenced(const RowMatrix& x, const RowMatrix& xp, Evaluation& out,
                                         bool hessian) const {
  // Per row: x, x +- h_i e_i, and for the Hessian x +- h_i e_i +- h_j e_j (i < j): 1 + 2d^2
  // points (1 + 2d for the gradient alone), all in one call.
  const Eigen::Index k = x.rows(), d = x.cols();
  const Eigen::Index m = hessian ? 1 + 2 * d * d : 1 + 2 * d;
  const double c = hessian ? std::sqrt(std::sqrt(kEps)) : std::cbrt(kEps);
  RowMatrix pts(k * m, d), h(k, d);
  for (Eigen::Index r = 0; r < k; ++r) {
    h.row(r) = steps(x.row(r).transpose(), c).transpose();
    Eigen::Index p = r * m;
    pts.row(p++) = x.row(r);
    for (Eigen::Index i = 0; i < d; ++i)
      for (const double s : {1.0, -1.0}) {
        pts.row(p) = x.row(r);
        pts(p++, i) += s * h(r, i);
      }
    if (!hessian) continue;
    for (Eigen::Index i = 0; i < d; ++i)
      for (Eigen::Index j = i + 1; j < d; ++j)
        for (const double si : {1.0, -1.0})
          for (const double sj : {1.0, -1.0}) {
            pts.row(p) = x.row(r);
            pts(p, i) += si * h(r, i);
            pts(p++, j) += sj * h(r, j);
          }
  }
  const VecX f = cb.objective(pts, repeat_rows(xp, m));
  out.value.resize(k);
  out.gradient.resize(k, d);
  for (Eigen::Index r = 0; r < k; ++r) {
    const Eigen::Index p0 = r * m;
    const double f0 = f[p0];
    out.value[r] = f0;
    for (Eigen::Index i = 0; i < d; ++i)
      out.gradient(r, i) = (f[p0 + 1 + 2 * i] - f[p0 + 2 + 2 * i]) / (2.0 * h(r, i));
    if (!hessian) continue;
    Eigen::Map<RowMatrix> hr = out.hessian_at(r);
    for (Eigen::Index i = 0; i < d; ++i)
      hr(i, i) = (f[p0 + 1 + 2 * i] - 2.0 * f0 + f[p0 + 2 + 2 * i]) / (h(r, i) * h(r, i));
    Eigen::Index p = p0 + 1 + 2 * d;
    for (Eigen::Index i = 0; i < d; ++i)
      for (Eigen::Index j = i + 1; j < d; ++j) {
        const double fpp = f[p], fpm = f[p + 1], fmp = f[p + 2], fmm = f[p + 3];
        p += 4;
        hr(i, j) = hr(j, i) = (fpp - fpm - fmp + fmm) / (4.0 * h(r, i) * h(r, j));
      }
  }
}

}  // namespace implicit::python::ssm
