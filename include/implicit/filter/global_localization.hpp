#pragma once
// Global localization (spec §3.11): particles for the first detections when the initial pose is
// unknown.
//
// The target is t(x) = u(x) p(z | x) over poses x = (x, y, heading), with u uniform over the
// landmarks' bounding box grown by a margin and over all headings, and p(z | x) the likelihood of
// the landmark observation model (robot/landmark_observation.hpp: ML association at x, clutter for
// the dropped), which the bootstrap weights by.
// Its mass sits near the minima of F(x) = -log p(z | x), usually several (a symmetric map, or
// unlabelled detections that fit several places). They are found by a multi-start Newton:
//
//   PoseBounds b = map_bounds(map.positions(), 5.0);
//   const auto d = model.view(detections);           // robot::LandmarkDetections
//   std::vector<Laplace<3>> modes = find_pose_modes(d, b, GlobalInitOptions{});
//   sample_pose_mixture(d, modes, b, seed, step, particles, log_weights);
//
// find_pose_modes starts a Newton from every point of a coarse cover (grid in x, y; a few
// headings), with the detections associated at the start under a pose covariance as coarse as
// the cover, and F built from that association with no prior (its constants kept, so phi values of
// different minima compare). A minimum is re-associated at itself and polished until its
// association is stable, so it is a minimum of -log p(z | x) itself. Minima closer than
// merge_distance are one mode (the lowest phi is kept).
//
// sample_pose_mixture draws from q = sum_k pi_k N(mu_k, H_k^-1) (MixtureProposal's pi_k) and
// weights by t(x) / q(x): E_q[w] = Z = integral of t, exactly, for any set of modes, even a poor
// one. The heading: q lives on R^3 while t is 2 pi-periodic in the heading; a drawn heading is
// wrapped to [-pi, pi), so the density of the wrapped draw is the sum of q over all 2 pi shifts of
// the heading. We sum the shifts that matter per component (see detail::WrappedMixture), which is
// exact to round-off; for the narrow components of a localization problem (heading std well
// below pi) only the shift nearest the component's centre is above round-off.
//
// Not covered by the modes: with clutter on, each detection's likelihood is at least p0 (ML
// association at x with S = Sigma2: inside the gate N(e; 0, Sigma2) >= p0), so p(z | x) >= p0^n
// over the whole box and Z >= p0^n. The weights stay unbiased, but when that floor holds a
// noticeable part of Z the modes alone almost never sample it and the estimate of Z (and the
// posterior) misses it. `uniform_fraction` > 0 adds u itself as a defensive component,
// q' = (1 - eps) q + eps u, which bounds every weight by p(z | x) / eps.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/laplace.hpp"
#include "implicit/core/mixture.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/filter/proposals.hpp"

namespace implicit::filter {

/// A box in (x, y); headings cover all of [-pi, pi).
struct PoseBounds {
  double x_min, x_max, y_min, y_max;
  bool contains(const Pose& x) const {
    return x(0) >= x_min && x(0) <= x_max && x(1) >= y_min && x(1) <= y_max;
  }
};

/// The landmarks' bounding box grown by `margin` on every side (error if the map is empty or the
/// box has no area).
inline PoseBounds map_bounds(std::span<const Landmark> map, double margin) {
  require(!map.empty(), "global localization: expected a map with at least one landmark, got none");
  require(margin >= 0 && std::isfinite(margin),
          "global localization: expected a finite non-negative margin, got {}", margin);
  PoseBounds b{map[0](0), map[0](0), map[0](1), map[0](1)};
  for (const Landmark& m : map) {
    require(m.allFinite(), "global localization: expected finite landmarks, got ({}, {})", m(0),
            m(1));
    b.x_min = std::min(b.x_min, m(0));
    b.x_max = std::max(b.x_max, m(0));
    b.y_min = std::min(b.y_min, m(1));
    b.y_max = std::max(b.y_max, m(1));
  }
  b.x_min -= margin;
  b.x_max += margin;
  b.y_min -= margin;
  b.y_max += margin;
  require(b.x_max > b.x_min && b.y_max > b.y_min,
          "global localization: expected a pose box of positive area, got [{}, {}] x [{}, {}] "
          "(use a positive margin)",
          b.x_min, b.x_max, b.y_min, b.y_max);
  return b;
}

/// log u(x) = -log(area * 2 pi) inside the box.
inline double log_uniform_density(const PoseBounds& b) {
  const double area = (b.x_max - b.x_min) * (b.y_max - b.y_min);
  require(area > 0 && std::isfinite(area),
          "global localization: expected a pose box of positive finite area, got {}", area);
  return -std::log(area * 2.0 * kPi);
}

struct GlobalInitOptions {
  double cover_spacing = 2.0;   ///< [m] grid spacing of the Newton starts in x and y
  int cover_headings = 8;       ///< headings per grid point
  double margin = 5.0;          ///< [m] the bounds: landmarks' box grown by this
  double merge_distance = 0.3;  ///< minima closer than this (Mahalanobis-free: metres, heading
                                ///< difference wrapped and scaled by 1 m/rad) are one mode
  std::size_t max_modes = 2000;
  int min_detections = 2;  ///< fewer associated detections at a start: skip that start (F is
                           ///< flat along a curve with one detection)
  /// Modes whose mixture weight pi_k is below exp(-max_log_weight_gap) times the largest are left
  /// out: never drawn (a uniform has 53 bits), so they would only cost time in q. Leaving out
  /// components keeps the weights exact (any mixture is a valid proposal).
  double max_log_weight_gap = 40.0;
  int max_reassociations = 4;  ///< polishing rounds (re-associate at the minimum, Newton again)
  NewtonOptions newton = mcl_newton_options();
};

struct GlobalInitStats {
  std::size_t starts = 0;      ///< Newton starts of the cover
  std::size_t skipped = 0;     ///< starts with fewer than min_detections associated
  std::size_t converged = 0;   ///< finite minima with an SPD Hessian inside the bounds
  std::size_t degenerate = 0;  ///< of those, left out: heading std above pi/3
  std::size_t modes = 0;       ///< after merging (and max_modes)
  std::size_t negligible = 0;  ///< distinct minima left out by max_log_weight_gap
  std::size_t truncated = 0;   ///< distinct minima left out by max_modes
  long evaluations = 0;        ///< objective evaluations (with derivatives) of all Newton runs
};

namespace detail {

/// Heading std above which a mode is degenerate (the wrap of its draws would not be exact with a
/// few shifts, and a mode so wide in heading locates nothing).
inline constexpr double kMaxHeadingStd = kPi / 3.0;

/// Distance of two poses for merging: metres, heading difference wrapped at 1 m/rad.
inline double pose_distance(const Pose& a, const Pose& b) {
  const double dh = wrap_angle(a(2) - b(2));
  return std::sqrt((a(0) - b(0)) * (a(0) - b(0)) + (a(1) - b(1)) * (a(1) - b(1)) + dh * dh);
}

/// The association of every detection at x: labels kept; ML with pose covariance pose_cov (nullptr:
/// Sigma2 alone, as in the likelihood).
template <typename Sensor>
int associate_all(const robot::LandmarkDetections<Sensor>& d, const Pose& x, const Mat3* pose_cov,
                  std::span<int> out) {
  int used = 0;
  for (std::size_t i = 0; i < d.z.size(); ++i) {
    const LabelledMeasurement& lz = d.z[i];
    out[i] = lz.landmark >= 0 ? lz.landmark : d.model->associate(x, pose_cov, lz.z);
    used += out[i] >= 0 ? 1 : 0;
  }
  return used;
}

/// F(x) = -log p(z | x) of a fixed association: no prior, constants kept (1/2 log det 2 pi Sigma2
/// per associated detection, -log p0 per dropped one when clutter is on).
template <typename Sensor>
void build_objective(const robot::LandmarkDetections<Sensor>& d, std::span<const int> assoc,
                     MclObjective<Sensor>& obj) {
  const robot::LandmarkObservation<Sensor>& model = *d.model;
  obj.reset(model.sensor(), model.noise_information(), Pose::Zero(), Mat3::Zero(), 0.0);
  const double per_term = gaussian_log_normaliser(2, 0.5 * model.log_det_noise());
  for (std::size_t i = 0; i < d.z.size(); ++i) {
    const int k = assoc[i];
    if (k < 0 || !obj.add(model.landmarks()[static_cast<std::size_t>(k)], d.z[i].z)) {
      if (model.association().clutter) obj.add_constant(-model.log_clutter());
      continue;
    }
    obj.add_constant(per_term);
  }
}

/// One start of the cover: Newton from x0 with the association at x0, then polishing rounds.
/// Returns false when the start is skipped (too few detections) or gives no usable minimum.
template <typename Sensor>
bool newton_from_start(const robot::LandmarkDetections<Sensor>& d, const Pose& x0,
                       const Mat3& cover_cov, const GlobalInitOptions& o, PoseMinimum& out,
                       bool& skipped) {
  constexpr std::size_t kMax = MclObjective<Sensor>::kMaxTerms;
  // F holds at most kMax terms: further detections enter phi as clutter (the modes are only a
  // proposal, so this costs efficiency, never exactness).
  const std::size_t n = std::min(d.z.size(), kMax);
  std::array<int, kMax> a{}, b{};
  const std::span<int> assoc(a.data(), n), next(b.data(), n);
  robot::LandmarkDetections<Sensor> head = d;
  head.z = d.z.first(n);
  skipped = associate_all(head, x0, &cover_cov, assoc) < o.min_detections;
  if (skipped) return false;
  MclObjective<Sensor> obj;
  Pose start = x0;
  int evaluations = 0;
  for (int round = 0;; ++round) {
    build_objective(head, assoc, obj);
    out = newton_minimize<SmallFactor<3>>(obj, start, o.newton);
    evaluations += out.evaluations;
    if (!usable(out) || !out.converged() || round >= o.max_reassociations) break;
    associate_all(head, out.x, nullptr, next);
    if (std::equal(assoc.begin(), assoc.end(), next.begin())) break;
    std::copy(next.begin(), next.end(), assoc.begin());
    start = out.x;
  }
  out.evaluations = evaluations;
  if (d.z.size() > n && d.model->association().clutter)  // the detections F could not hold
    out.value -= static_cast<double>(d.z.size() - n) * d.model->log_clutter();
  out.x(2) = wrap_angle(out.x(2));
  return usable(out) && out.converged() && out.x.allFinite() && std::isfinite(out.value);
}

/// The density of a wrapped draw of a Gaussian mixture on R^3: the heading of x lies in
/// [-pi, pi) and the density is sum_k pi_k sum_n N(x + 2 pi n e3; mu_k, H_k^-1).
///
/// Per component, the quadratic form Q(s) = |L^T (x - mu + s e3)|^2 along the heading shift s is
/// minimal at s* with curvature h = H_33 >= 1 / Var(heading) (a conditional precision bounds the
/// marginal one). The shift nearest s* is within pi of it; shifts beyond (2K + 1) pi of s* have
/// density ratios below exp(-h pi^2 ((2K + 1)^2 - 1) / 2) to it. K is chosen per component so that
/// this is below exp(-40) (~4e-18): every shift above round-off is summed. For the components of a
/// localization problem (heading std of a few degrees) K = 1: three shifts, of which only the one
/// nearest the component's centre is above round-off.
class WrappedMixture {
 public:
  explicit WrappedMixture(const MixtureProposal<3>& mix) {
    const auto& comps = mix.components();
    terms_.reserve(comps.size());
    for (std::size_t k = 0; k < comps.size(); ++k) {
      Term t;
      t.mu = comps[k].mu;
      t.lt = comps[k].L.transpose();
      t.c = comps[k].L.row(2).transpose();  // L^T e3
      t.h = t.c.squaredNorm();
      // Var(heading) = 1 / L_22^2 <= pi^2 bounds h >= L_22^2 >= 1 / pi^2, so reach <= 4.
      require(comps[k].L(2, 2) * kPi >= 1.0,
              "global localization: expected mixture components with a heading std of at most pi, "
              "got {} for component {}",
              1.0 / comps[k].L(2, 2), k);
      t.log_norm =
          mix.log_mixture_weights()[k] - gaussian_log_normaliser(3, 0.0) + comps[k].log_det_L;
      t.reach = 1;
      while (0.5 * t.h * kPi * kPi * ((2.0 * t.reach + 1) * (2.0 * t.reach + 1) - 1.0) < 40.0)
        ++t.reach;
      terms_.push_back(t);
    }
  }

  /// log of the wrapped density at x (heading in [-pi, pi)). Streaming log-sum-exp.
  double log_density(const Pose& x) const {
    double top = -std::numeric_limits<double>::infinity(), sum = 0.0;
    for (const Term& t : terms_) {
      const Vec<3> a = t.lt * (x - t.mu);
      const double s_star = -a.dot(t.c) / t.h;
      const double half = (2.0 * t.reach + 1) * kPi;
      const long n_lo = static_cast<long>(std::ceil((s_star - half) / (2.0 * kPi)));
      const long n_hi = static_cast<long>(std::floor((s_star + half) / (2.0 * kPi)));
      for (long n = n_lo; n <= n_hi; ++n) {
        const Vec<3> v = a + (2.0 * kPi * static_cast<double>(n)) * t.c;
        const double term = t.log_norm - 0.5 * v.squaredNorm();
        if (!(term > -std::numeric_limits<double>::infinity())) continue;
        if (term > top) {
          sum = sum * std::exp(top - term) + 1.0;
          top = term;
        } else {
          sum += std::exp(term - top);
        }
      }
    }
    return sum > 0.0 ? top + std::log(sum) : -std::numeric_limits<double>::infinity();
  }

 private:
  struct Term {
    Vec<3> mu;
    Mat3 lt;  ///< L^T
    Vec<3> c;
    double h = 0.0;
    double log_norm = 0.0;  ///< log pi_k - 3/2 log 2 pi + log det L
    int reach = 1;
  };
  std::vector<Term> terms_;
};

}  // namespace detail

/// Per start x0 of the cover (grid points at the centres of spacing x spacing cells covering the
/// bounds, headings -pi + 2 pi k / cover_headings): associate every detection at x0 with pose
/// covariance diag(spacing^2, spacing^2, (pi / headings)^2) (the gate reflects the cover's
/// coarseness), build F = -log p(z | x) of that association with no prior, minimise from x0,
/// re-associate at the minimum and polish; keep finite minima with an SPD L inside the bounds and a
/// heading std of at most pi/3; merge duplicates (keep the lowest phi); leave out the negligible
/// (max_log_weight_gap) and those beyond max_modes. Returns the Laplace<3>
/// components (headings in [-pi, pi)), sorted by phi. Parallel over starts, deterministic.
template <typename Sensor>
std::vector<Laplace<3>> find_pose_modes(const robot::LandmarkDetections<Sensor>& d,
                                        const PoseBounds& b, const GlobalInitOptions& o,
                                        GlobalInitStats* stats = nullptr) {
  require(o.cover_spacing > 0 && std::isfinite(o.cover_spacing),
          "global localization: expected a positive cover spacing, got {}", o.cover_spacing);
  require(o.cover_headings >= 1, "global localization: expected at least 1 cover heading, got {}",
          o.cover_headings);
  require(o.min_detections >= 1,
          "global localization: expected min_detections of at least 1, got {}", o.min_detections);
  require(o.merge_distance >= 0,
          "global localization: expected a non-negative merge distance, got {}", o.merge_distance);
  require(b.x_max > b.x_min && b.y_max > b.y_min,
          "global localization: expected a pose box of positive area, got [{}, {}] x [{}, {}]",
          b.x_min, b.x_max, b.y_min, b.y_max);
  const double s = o.cover_spacing;
  const auto cells = [s](double lo, double hi) {
    return static_cast<std::size_t>(std::max(1.0, std::ceil((hi - lo) / s)));
  };
  const std::size_t nx = cells(b.x_min, b.x_max), ny = cells(b.y_min, b.y_max);
  const auto nh = static_cast<std::size_t>(o.cover_headings);
  require(static_cast<double>(nx) * static_cast<double>(ny) * static_cast<double>(nh) <= 1e8,
          "global localization: expected at most 1e8 starts, got {} x {} x {} (coarser cover)", nx,
          ny, nh);
  const std::size_t starts = nx * ny * nh;
  const double dh = kPi / static_cast<double>(nh);
  const Mat3 cover_cov = Vec<3>(s * s, s * s, dh * dh).asDiagonal();
  std::vector<PoseMinimum> found(starts);
  std::vector<unsigned char> status(starts, 0);  // 0 no minimum, 1 skipped, 2 minimum
  parallel_for(
      starts,
      [&](std::size_t i) {
        const std::size_t ih = i % nh, ixy = i / nh, iy = ixy % ny, ix = ixy / ny;
        // Cell centres, clamped to the box when the last cell overhangs it.
        const Pose x0(std::min(b.x_min + (static_cast<double>(ix) + 0.5) * s, b.x_max),
                      std::min(b.y_min + (static_cast<double>(iy) + 0.5) * s, b.y_max),
                      -kPi + 2.0 * dh * static_cast<double>(ih));
        bool skipped = false;
        const bool ok = detail::newton_from_start(d, x0, cover_cov, o, found[i], skipped);
        status[i] = skipped ? 1 : (ok && b.contains(found[i].x) ? 2 : 0);
      },
      4);
  GlobalInitStats st;
  st.starts = starts;
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < starts; ++i) {
    st.evaluations += found[i].evaluations;
    st.skipped += status[i] == 1 ? 1 : 0;
    if (status[i] != 2) continue;
    ++st.converged;
    // H^-1 = L^-T L^-1, so Var(heading) = 1 / L_22^2.
    if (1.0 / found[i].factor.matrixL()(2, 2) > detail::kMaxHeadingStd)
      ++st.degenerate;
    else
      order.push_back(i);
  }
  // Lowest phi first; ties by start index, so the result does not depend on the thread count.
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t i, std::size_t j) { return found[i].value < found[j].value; });
  double best_log_weight = -std::numeric_limits<double>::infinity();  // max of -phi - log det L
  for (const std::size_t i : order)
    best_log_weight = std::max(best_log_weight, -found[i].value - found[i].factor.log_det_L());
  std::vector<Laplace<3>> modes;
  for (const std::size_t i : order) {
    const bool duplicate = std::any_of(modes.begin(), modes.end(), [&](const Laplace<3>& m) {
      return detail::pose_distance(m.mu, found[i].x) < o.merge_distance;
    });
    if (duplicate) continue;
    if (-found[i].value - found[i].factor.log_det_L() < best_log_weight - o.max_log_weight_gap) {
      ++st.negligible;
      continue;
    }
    if (modes.size() == o.max_modes) {
      ++st.truncated;
      continue;
    }
    Laplace<3> lp;
    lp.mu = found[i].x;
    lp.phi = found[i].value;
    lp.L = found[i].factor.matrixL();
    lp.log_det_L = found[i].factor.log_det_L();
    modes.push_back(lp);
  }
  st.modes = modes.size();
  if (stats) *stats = st;
  return modes;
}

/// A pose uniform over the box and all headings, from three uniforms of rng.
inline Pose uniform_pose(const PoseBounds& b, Rng& rng) {
  const double ux = rng.uniform(), uy = rng.uniform(), uh = rng.uniform();
  return Pose(b.x_min + ux * (b.x_max - b.x_min), b.y_min + uy * (b.y_max - b.y_min),
              -kPi + 2.0 * kPi * uh);
}

/// One draw at a time from the mixture over `modes` (pi_k as in MixtureProposal), optionally
/// defensive: the proposal is (1 - eps) q + eps u, eps = uniform_fraction in [0, 1). A draw takes
/// one uniform u0 from its stream: u0 < eps gives a uniform pose (three more uniforms), else the
/// component choice (u0 - eps) / (1 - eps) and three normals. Its log weight is
/// log u(x) + log p(z | x) - log proposal(x) (-inf outside the box; p: the model's likelihood),
/// with q summed over the heading's 2 pi shifts (detail::WrappedMixture). Throws InvalidArgument
/// when `modes` is empty (no pose explains the detections).
class PoseMixtureSampler {
 public:
  PoseMixtureSampler(std::vector<Laplace<3>> modes, const PoseBounds& b,
                     double uniform_fraction = 0.0)
      : mix_(checked(std::move(modes))),
        q_(mix_),
        bounds_(b),
        eps_(uniform_fraction),
        log_u_(log_uniform_density(b)) {
    require(uniform_fraction >= 0 && uniform_fraction < 1,
            "global localization: expected a uniform fraction in [0, 1), got {}", uniform_fraction);
    log_eps_u_ = std::log(eps_) + log_u_;
    log_mix_ = std::log1p(-eps_);
  }

  template <typename Sensor>
  double draw(const robot::LandmarkDetections<Sensor>& d, Rng& rng, Pose& x) const {
    const double u = rng.uniform();
    if (u < eps_) {
      x = uniform_pose(bounds_, rng);
    } else {
      const Vec<3> xi = rng.normal_vector<3>();
      x = mix_.components()[mix_.choose((u - eps_) / (1.0 - eps_))].map(xi);  // eps = 0: u
      x(2) = wrap_angle(x(2));
    }
    if (!x.allFinite() || !bounds_.contains(x)) return -std::numeric_limits<double>::infinity();
    double log_q = log_mix_ + q_.log_density(x);
    if (eps_ > 0) {  // log((1 - eps) q + eps u)
      const double hi = std::max(log_q, log_eps_u_), lo = std::min(log_q, log_eps_u_);
      log_q = hi + std::log1p(std::exp(lo - hi));
    }
    return log_u_ + d.model->log_likelihood(d, x) - log_q;
  }

 private:
  static std::vector<Laplace<3>> checked(std::vector<Laplace<3>> modes) {
    require(!modes.empty(),
            "global localization: no pose explains the detections (no minimum of -log p(z | x) "
            "was found inside the bounds; more detections, a finer cover or a larger margin may "
            "help)");
    return modes;
  }

  MixtureProposal<3> mix_;
  detail::WrappedMixture q_;
  PoseBounds bounds_;
  double eps_, log_u_, log_eps_u_ = 0.0, log_mix_ = 0.0;
};

/// Draws particles with PoseMixtureSampler; particle j uses Rng({seed, step, j,
/// purpose::kGlobalInit}). Parallel over particles, bit-identical for any thread count.
template <typename Sensor>
void sample_pose_mixture(const robot::LandmarkDetections<Sensor>& d,
                         const std::vector<Laplace<3>>& modes, const PoseBounds& b,
                         std::uint64_t seed, std::uint64_t step, std::span<Pose> particles,
                         std::span<double> log_weights, double uniform_fraction = 0.0) {
  require(particles.size() == log_weights.size(),
          "global localization: expected as many log weights as particles, got {} and {}",
          log_weights.size(), particles.size());
  const PoseMixtureSampler sampler(modes, b, uniform_fraction);
  parallel_for(particles.size(), [&](std::size_t j) {
    Rng rng({.seed = seed, .step = step, .index = j, .purpose = purpose::kGlobalInit});
    log_weights[j] = sampler.draw(d, rng, particles[j]);
  });
}

/// Uniform cloud over the bounds and all headings (the bootstrap's global start); with equal
/// weights it is an exact sample of u. Particle j uses Rng({seed, 0, j, purpose::kGlobalInit}).
inline void sample_uniform_poses(const PoseBounds& b, std::uint64_t seed,
                                 std::span<Pose> particles) {
  require(b.x_max > b.x_min && b.y_max > b.y_min,
          "global localization: expected a pose box of positive area, got [{}, {}] x [{}, {}]",
          b.x_min, b.x_max, b.y_min, b.y_max);
  parallel_for(particles.size(), [&](std::size_t j) {
    Rng rng({.seed = seed, .step = 0, .index = j, .purpose = purpose::kGlobalInit});
    particles[j] = uniform_pose(b, rng);
  });
}

}  // namespace implicit::filter
