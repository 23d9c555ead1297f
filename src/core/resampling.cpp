#include "implicit/core/resampling.hpp"

#include <algorithm>
#include <cmath>

#include "implicit/core/error.hpp"

namespace implicit {

std::string_view to_string(ResamplingScheme s) {
  switch (s) {
    case ResamplingScheme::kMultinomial:
      return "multinomial";
    case ResamplingScheme::kSystematic:
      return "systematic";
    case ResamplingScheme::kStratified:
      return "stratified";
    case ResamplingScheme::kResidual:
      return "residual";
  }
  return "unknown";
}

ResamplingScheme parse_resampling_scheme(std::string_view name) {
  for (auto s : {ResamplingScheme::kMultinomial, ResamplingScheme::kSystematic,
                 ResamplingScheme::kStratified, ResamplingScheme::kResidual})
    if (name == to_string(s)) return s;
  throw InvalidArgument(fmt::format(
      "resampling scheme: expected multinomial, systematic, stratified or residual, got '{}'",
      name));
}

std::size_t uniforms_needed(ResamplingScheme scheme, std::size_t n) {
  return scheme == ResamplingScheme::kSystematic ? 1 : n;
}

namespace {

void validate(std::span<const double> w, std::span<const double> u, std::size_t needed) {
  require(!w.empty(), "resample: expected at least one weight, got none");
  double sum = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    require(std::isfinite(w[i]) && w[i] >= 0.0,
            "resample: weight {} is {} (expected a finite non-negative number)", i, w[i]);
    sum += w[i];
  }
  require(std::abs(sum - 1.0) <= 1e-8,
          "resample: expected normalised weights summing to 1, got a sum of {}", sum);
  require(u.size() >= needed, "resample: expected {} uniforms, got {}", needed, u.size());
  for (std::size_t i = 0; i < needed; ++i)
    require(u[i] > 0.0 && u[i] < 1.0, "resample: uniform {} is {} (expected a value in (0, 1))", i,
            u[i]);
}

// Inverse CDF for `count` sorted points point(0) <= point(1) <= ... in [0, 1): the ancestor of
// each point is appended to `out`. Points are generated on the fly (no array for systematic and
// stratified schemes). The ancestor is clamped to the last particle of positive weight, so that
// round-off in the cumulative sum (which may end slightly below 1) never indexes past the end nor
// picks a trailing zero-weight particle.
template <typename Point>
void inverse_cdf(std::span<const double> w, std::size_t count, Point point,
                 std::vector<std::size_t>& out) {
  std::size_t last = w.size() - 1;
  while (last > 0 && !(w[last] > 0.0)) --last;
  std::size_t i = 0;
  double cumulative = w[0];
  for (std::size_t k = 0; k < count; ++k) {
    const double s = point(k);
    while (s >= cumulative && i < last) cumulative += w[++i];
    out.push_back(i);
  }
}

}  // namespace

void resample(ResamplingScheme scheme, std::span<const double> w, std::span<const double> u,
              std::size_t n, std::vector<std::size_t>& out) {
  validate(w, u, uniforms_needed(scheme, n));
  out.clear();
  out.reserve(n + 1);  // the systematic scheme uses one extra slot while working
  if (n == 0) return;
  const double dn = static_cast<double>(n);
  switch (scheme) {
    case ResamplingScheme::kSystematic: {
      // Points (k + u)/n, k = 0..n-1. Particle i takes the points below its cumulative weight
      // C_i that particle i-1 did not take: k < e_i = ceil(n C_i - u). Instead of walking the
      // points (a data-dependent branch per point and per particle, mispredicted for fresh
      // weights) we mark o[e_i] = i + 1 and take a running maximum, so ancestor(k) =
      // #{i : e_i <= k}. Branch-free, two passes; e_i is monotone in i, so this is exactly the
      // inverse CDF, and a zero-weight particle (e_i = e_{i-1}) is never chosen. Particles after
      // the last positive weight are excluded as in inverse_cdf.
      std::size_t last = w.size() - 1;
      while (last > 0 && !(w[last] > 0.0)) --last;
      const double u0 = u[0];
      out.assign(n + 1, 0);
      std::size_t* o = out.data();
      double cumulative = 0.0;
      for (std::size_t i = 0; i < last; ++i) {
        cumulative += w[i];
        const double e = std::clamp(std::ceil(cumulative * dn - u0), 0.0, dn);
        o[static_cast<std::size_t>(e)] = i + 1;
      }
      std::size_t ancestor = 0;
      for (std::size_t k = 0; k < n; ++k) {
        ancestor = std::max(ancestor, o[k]);
        o[k] = ancestor;
      }
      out.pop_back();
      break;
    }
    case ResamplingScheme::kStratified:
      inverse_cdf(
          w, n, [&](std::size_t k) { return (static_cast<double>(k) + u[k]) / dn; }, out);
      break;
    case ResamplingScheme::kMultinomial: {
      std::vector<double> points(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(n));
      std::sort(points.begin(), points.end());
      inverse_cdf(
          w, n, [&](std::size_t k) { return points[k]; }, out);
      break;
    }
    case ResamplingScheme::kResidual: {
      // Deterministic floor(n w_i) copies, then multinomial on the residual weights.
      std::vector<double> residual(w.size());
      std::size_t copied = 0;
      for (std::size_t i = 0; i < w.size(); ++i) {
        const double nw = dn * w[i];
        const auto c = static_cast<std::size_t>(std::floor(nw));
        for (std::size_t k = 0; k < c && copied < n; ++k, ++copied) out.push_back(i);
        residual[i] = nw - static_cast<double>(c);
      }
      const std::size_t rest = n - copied;
      if (rest > 0) {
        double total = 0.0;
        for (double r : residual) total += r;
        for (double& r : residual) r /= total;
        std::vector<double> points(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(rest));
        std::sort(points.begin(), points.end());
        inverse_cdf(
            residual, rest, [&](std::size_t k) { return points[k]; }, out);
        std::sort(out.begin(), out.end());
      }
      break;
    }
  }
}

std::vector<std::size_t> resample(ResamplingScheme scheme, std::span<const double> w,
                                  std::span<const double> u, std::size_t n) {
  std::vector<std::size_t> out;
  resample(scheme, w, u, n, out);
  return out;
}

std::vector<std::size_t> resample(ResamplingScheme scheme, std::span<const double> w, std::size_t n,
                                  Rng& rng) {
  std::vector<double> u(uniforms_needed(scheme, n));
  for (double& x : u) x = rng.uniform();
  return resample(scheme, w, u, n);
}

bool needs_resampling(double ess, std::size_t m, double threshold) {
  require(threshold >= 0.0 && threshold <= 1.0,
          "resampling threshold: expected a fraction in [0, 1], got {}", threshold);
  require(!std::isnan(ess), "resampling: the effective sample size is NaN");
  return ess < threshold * static_cast<double>(m);
}

}  // namespace implicit
