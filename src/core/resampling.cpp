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

// Inverse CDF for sorted points s_0 <= s_1 <= ... in [0, 1): the ancestor of each point.
// The ancestor is clamped to the last particle of positive weight, so that round-off in the
// cumulative sum (which may end slightly below 1) never indexes past the end nor picks a
// trailing zero-weight particle.
void inverse_cdf(std::span<const double> w, std::span<const double> sorted_points,
                 std::vector<std::size_t>& out) {
  std::size_t last = w.size() - 1;
  while (last > 0 && !(w[last] > 0.0)) --last;
  std::size_t i = 0;
  double cumulative = w[0];
  for (double s : sorted_points) {
    while (s >= cumulative && i < last) cumulative += w[++i];
    out.push_back(i);
  }
}

}  // namespace

std::vector<std::size_t> resample(ResamplingScheme scheme, std::span<const double> w,
                                  std::span<const double> u, std::size_t n) {
  validate(w, u, uniforms_needed(scheme, n));
  std::vector<std::size_t> out;
  out.reserve(n);
  if (n == 0) return out;
  std::vector<double> points(n);
  const double dn = static_cast<double>(n);
  switch (scheme) {
    case ResamplingScheme::kSystematic:
      for (std::size_t k = 0; k < n; ++k) points[k] = (static_cast<double>(k) + u[0]) / dn;
      inverse_cdf(w, points, out);
      break;
    case ResamplingScheme::kStratified:
      for (std::size_t k = 0; k < n; ++k) points[k] = (static_cast<double>(k) + u[k]) / dn;
      inverse_cdf(w, points, out);
      break;
    case ResamplingScheme::kMultinomial:
      std::copy(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(n), points.begin());
      std::sort(points.begin(), points.end());
      inverse_cdf(w, points, out);
      break;
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
        points.assign(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(rest));
        std::sort(points.begin(), points.end());
        inverse_cdf(residual, points, out);
        std::sort(out.begin(), out.end());
      }
      break;
    }
  }
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
