// Laser likelihood-field costs at 100 beams (LikelihoodFieldParams::max_beams), per particle, on
// the map of the Intel Research Lab log (data/carmen/intel-corrected.log.gz, built from its
// reference poses by experiments::load_laser_dataset) with the log's own scans:
//  * LogLikelihood/<interpolation>: LikelihoodFieldModel::log_likelihood, what the bootstrap
//    proposal pays per particle;
//  * NegLogLikelihood/bicubic: -log p with its gradient and Gauss-Newton matrix, one objective
//    evaluation of the implicit proposal's Newton iteration;
//  * FilterUpdate/<proposal>/<interpolation>: one update step of MonteCarloLocalization with
//    OdometryModel (prediction, weighting, normalisation, resampling when ESS < M / 2) on ONE
//    thread, M = 1000 particles (reset, untimed, before each update); the counter evaluations
//    is the implicit proposal's Newton evaluations per particle;
//  * NearestTable/build: the one-time tabulation behind nearest-cell interpolation.
// One iteration covers every particle of every benchmarked update (16 x 1000), so that every
// benchmark does the same work: read the counter per_particle, the CPU time per particle.
//
// Every benchmark runs on the model ("current") and on `baseline`, a copy kept here of the model
// as it was before its speed work (commit 43763d1), so that one run shows both side by side.
// Before any benchmark runs, the program checks that the two agree on every particle (to the
// rounding derived in check_agreement) and stops if they do not.
//
// Particles: at 16 updates spread over the log, 1000 poses drawn around the previous reference
// pose (sd 0.1 m, 0.1 m, 0.05 rad: the filter's particles before the update) and moved to the
// update by the odometry model's sampler (alphas 0.05, the laser experiment's default).
// Without the log (no data folder), a synthetic room with ray-cast scans stands in, and every
// benchmark's label says so.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "experiments/laser_mcl.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/filter/monte_carlo_localization.hpp"
#include "implicit/robot/beam_model.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/scan_simulation.hpp"

namespace {

using namespace implicit;
using robot::Interpolation;
using robot::Pose;

constexpr std::size_t kUpdates = 16;
constexpr std::size_t kParticles = 1000;
constexpr int kBeams = 100;
const robot::OdometryAlphas kAlphas{0.05, 0.05, 0.05, 0.05};

namespace baseline {

// The distance field's lookup and the likelihood field as they were before the speed work, kept
// as the "before" of every benchmark. The cells are copied from the current field
// (cell_distance), laid out as that version stored them: row-major with `pad` cells around.
class Field {
 public:
  explicit Field(const robot::DistanceField& f)
      : width_(f.width()),
        height_(f.height()),
        inv_resolution_(1.0 / f.resolution()),
        origin_(f.origin()),
        max_distance_(f.max_distance()),
        pad_(static_cast<int>(std::min(4096.0, std::ceil(max_distance_ / f.resolution()) + 3.0))),
        padded_width_(width_ + 2 * pad_) {
    const int padded_height = height_ + 2 * pad_;
    padded_.resize(static_cast<std::size_t>(padded_width_) *
                   static_cast<std::size_t>(padded_height));
    for (int py = 0; py < padded_height; ++py)
      for (int px = 0; px < padded_width_; ++px)
        padded_[static_cast<std::size_t>(py) * static_cast<std::size_t>(padded_width_) +
                static_cast<std::size_t>(px)] =
            static_cast<float>(f.cell_distance(px - pad_, py - pad_));
    u_lo_ = v_lo_ = -(pad_ - 2.0);
    u_hi_ = width_ + pad_ - 2.0;
    v_hi_ = height_ + pad_ - 2.0;
  }

  double max_distance() const { return max_distance_; }

  double distance(const Vec<2>& p, Interpolation mode, Vec<2>* gradient) const {
    const double u = (p.x() - origin_.x()) * inv_resolution_;
    const double v = (p.y() - origin_.y()) * inv_resolution_;
    if (!(u > u_lo_ && u < u_hi_ && v > v_lo_ && v < v_hi_)) {
      const bool nan = std::isnan(u) || std::isnan(v);
      const double value = nan ? std::numeric_limits<double>::quiet_NaN() : max_distance_;
      if (gradient != nullptr) gradient->setConstant(nan ? value : 0.0);
      return value;
    }
    if (mode == Interpolation::kNearest) {
      if (gradient != nullptr) gradient->setZero();
      return value_at(static_cast<int>(u + pad_) - pad_, static_cast<int>(v + pad_) - pad_);
    }
    const double a = u - 0.5, b = v - 0.5;
    const int i0 = static_cast<int>(a + pad_) - pad_, j0 = static_cast<int>(b + pad_) - pad_;
    const double tx = a - i0, ty = b - j0;
    if (mode == Interpolation::kBilinear) {
      float c[4];
      gather(i0, j0, 2, c);
      const double c00 = c[0], c10 = c[1], c01 = c[2], c11 = c[3];
      const double bottom = c00 + tx * (c10 - c00), top = c01 + tx * (c11 - c01);
      if (gradient != nullptr)
        *gradient = Vec<2>(((1 - ty) * (c10 - c00) + ty * (c11 - c01)) * inv_resolution_,
                           (top - bottom) * inv_resolution_);
      return bottom + ty * (top - bottom);
    }
    float c[16];
    gather(i0 - 1, j0 - 1, 4, c);
    double wx[4], dwx[4], wy[4], dwy[4];
    catmull_rom_weights(tx, wx, dwx);
    catmull_rom_weights(ty, wy, dwy);
    double value = 0.0, du = 0.0, dv = 0.0;
    for (int j = 0; j < 4; ++j) {
      double row = 0.0, drow = 0.0;
      for (int i = 0; i < 4; ++i) {
        row += wx[i] * c[j * 4 + i];
        drow += dwx[i] * c[j * 4 + i];
      }
      value += wy[j] * row;
      du += wy[j] * drow;
      dv += dwy[j] * row;
    }
    if (gradient != nullptr) *gradient = Vec<2>(du * inv_resolution_, dv * inv_resolution_);
    return value;
  }

 private:
  static void catmull_rom_weights(double t, double w[4], double dw[4]) {
    const double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2 * t2 - t);
    w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
    w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
    dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
    dw[1] = 0.5 * (9 * t2 - 10 * t);
    dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
    dw[3] = 0.5 * (3 * t2 - 2 * t);
  }
  float value_at(int ix, int iy) const {
    const int px = ix + pad_, py = iy + pad_;
    if (px < 0 || py < 0 || px >= padded_width_ || py >= height_ + 2 * pad_)
      return static_cast<float>(max_distance_);
    return padded_[static_cast<std::size_t>(py) * static_cast<std::size_t>(padded_width_) +
                   static_cast<std::size_t>(px)];
  }
  void gather(int ix, int iy, int n, float* out) const {
    if (ix >= -pad_ && iy >= -pad_ && ix + n <= width_ + pad_ && iy + n <= height_ + pad_) {
      const float* p =
          padded_.data() +
          static_cast<std::size_t>(iy + pad_) * static_cast<std::size_t>(padded_width_) +
          static_cast<std::size_t>(ix + pad_);
      for (int j = 0; j < n; ++j, p += padded_width_)
        for (int i = 0; i < n; ++i) out[j * n + i] = p[i];
      return;
    }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) out[j * n + i] = value_at(ix + i, iy + j);
  }

  int width_, height_;
  double inv_resolution_;
  Vec<2> origin_;
  double max_distance_;
  int pad_, padded_width_;
  std::vector<float> padded_;
  double u_lo_ = 0, u_hi_ = 0, v_lo_ = 0, v_hi_ = 0;
};

// The likelihood field's per-particle work as it was (the product aggregation only); prepare()
// is the current model's, whose beams and constants are unchanged.
class Model {
 public:
  using Observation = robot::LaserScan;
  using Prepared = robot::PreparedScan;

  Model(std::shared_ptr<const robot::DistanceField> field, const robot::LikelihoodFieldParams& p,
        const robot::LaserMount& mount)
      : current_(field, p, mount),
        field_(std::make_shared<const Field>(*field)),
        mode_(p.interpolation),
        max_distance_(std::min(p.laser_likelihood_max_dist, field->max_distance())),
        inv_var_(1.0 / (p.sigma_hit * p.sigma_hit)) {}

  Prepared prepare(const Observation& z, std::string_view where) const {
    return current_.prepare(z, where);
  }
  bool differentiable() const { return current_.differentiable(); }
  std::string_view why_not_differentiable() const { return current_.why_not_differentiable(); }

  double beam_log_density(const Prepared& z, double distance) const {
    const double h = z.log_hit_scale - 0.5 * distance * distance * inv_var_;
    const double c = z.rand_density;
    if (c <= 0.0) return h;
    const double lc = std::log(c);
    return h > lc ? h + std::log1p(std::exp(lc - h)) : lc + std::log1p(std::exp(h - lc));
  }

  double log_likelihood(const Prepared& z, const Pose& x) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    double total = 0.0;
    for (const Vec<2>& e : z.end_points) {
      const Vec<2> p(x(0) + c * e(0) - s * e(1), x(1) + s * e(0) + c * e(1));
      total += beam_log_density(z, std::min(field_->distance(p, mode_, nullptr), max_distance_));
    }
    return total;
  }

  double negative_log_likelihood(const Prepared& z, const Pose& x, Vec<3>* gradient,
                                 robot::Mat3* gauss_newton) const {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const bool derivatives = gradient != nullptr || gauss_newton != nullptr;
    double value = 0.0;
    Vec<3> g = Vec<3>::Zero();
    robot::Mat3 h = robot::Mat3::Zero();
    for (const Vec<2>& e : z.end_points) {
      const double ox = c * e(0) - s * e(1), oy = s * e(0) + c * e(1);
      Vec<2> grad_d;
      double d =
          field_->distance(Vec<2>(x(0) + ox, x(1) + oy), mode_, derivatives ? &grad_d : nullptr);
      if (d >= max_distance_) {
        d = max_distance_;
        grad_d.setZero();
      }
      const double log_hit = z.log_hit_scale - 0.5 * d * d * inv_var_;
      const double log_beam = beam_log_density(z, d);
      value -= log_beam;
      if (!derivatives) continue;
      const double gamma = std::exp(log_hit - log_beam);
      const double jx = grad_d(0), jy = grad_d(1), jt = -grad_d(0) * oy + grad_d(1) * ox;
      const double slope = gamma * d * inv_var_;
      g(0) += slope * jx;
      g(1) += slope * jy;
      g(2) += slope * jt;
      const double w = gamma * inv_var_;
      h(0, 0) += w * jx * jx;
      h(0, 1) += w * jx * jy;
      h(0, 2) += w * jx * jt;
      h(1, 1) += w * jy * jy;
      h(1, 2) += w * jy * jt;
      h(2, 2) += w * jt * jt;
    }
    if (gradient) *gradient += g;
    if (gauss_newton) {
      h(1, 0) = h(0, 1);
      h(2, 0) = h(0, 2);
      h(2, 1) = h(1, 2);
      *gauss_newton += h;
    }
    return value;
  }

 private:
  robot::LikelihoodFieldModel current_;  // for prepare() and the parameter checks
  std::shared_ptr<const Field> field_;
  Interpolation mode_;
  double max_distance_, inv_var_;
};

}  // namespace baseline

/// The map, the scans at the benchmarked updates, and the particles before and after moving.
struct Scene {
  std::string label;
  robot::OccupancyGrid map;
  robot::LaserMount mount;
  std::shared_ptr<const robot::DistanceField> field;
  std::vector<robot::LaserScan> scans;    // kUpdates
  std::vector<Vec<3>> controls;           // odometry increment into each update
  std::vector<std::vector<Pose>> before;  // the filter's particles before each update
  std::vector<std::vector<Pose>> moved;   // the same, moved by the odometry sampler
};

/// A 20 m x 15 m room with inner walls, and scans ray-cast along an ellipse through it.
experiments::LaserDataset synthetic_room() {
  experiments::LaserDataset d;
  const double res = 0.05;
  d.map = robot::OccupancyGrid(400, 300, res, Vec<2>::Zero(), robot::OccupancyGrid::kFree);
  auto wall = [&](double x0, double y0, double x1, double y1) {
    for (int iy = 0; iy < d.map.height(); ++iy)
      for (int ix = 0; ix < d.map.width(); ++ix) {
        const Vec<2> c = d.map.cell_center(ix, iy);
        if (c(0) >= x0 && c(0) <= x1 && c(1) >= y0 && c(1) <= y1)
          d.map.at(ix, iy) = robot::OccupancyGrid::kOccupied;
      }
  };
  wall(0, 0, 20, 0.1);
  wall(0, 14.9, 20, 15);
  wall(0, 0, 0.1, 15);
  wall(19.9, 0, 20, 15);
  wall(7, 0, 7.1, 4);
  wall(13, 11, 13.1, 15);
  wall(9, 7, 11, 8);
  robot::ScanSimulationOptions o;
  o.beams = 361;
  Rng rng({1, 0, 0, purpose::kData});
  for (int k = 0; k < 200; ++k) {
    const double a = 2 * kPi * k / 200.0;
    const Pose x(10 + 6 * std::cos(a), 7.5 + 4.5 * std::sin(a), a + kPi / 2);
    d.reference.push_back(x);
    d.scans.push_back(robot::simulate_scan(d.map, x, d.mount, o, rng));
  }
  return d;
}

Scene make_scene() {
  Scene s;
  experiments::LaserDataset d;
  std::filesystem::path log;
  try {
    log = find_share_dir("data", "IMPLICIT_DATA_DIR") / "carmen" / "intel-corrected.log.gz";
  } catch (const InvalidArgument&) {
  }
  if (!log.empty() && std::filesystem::exists(log)) {
    experiments::LaserDataOptions o;
    o.data = log;
    d = experiments::load_laser_dataset(o);
    s.label = "intel";
  } else {
    d = synthetic_room();
    s.label = "SYNTHETIC room (intel-corrected.log.gz not found)";
  }
  s.map = d.map;
  s.mount = d.mount;
  s.field = std::make_shared<const robot::DistanceField>(s.map, 2.0);
  const robot::OdometryModel motion(kAlphas);
  const std::size_t n = d.scans.size();
  for (std::size_t i = 0; i < kUpdates; ++i) {
    const std::size_t k = 1 + i * (n - 1) / kUpdates;
    s.scans.push_back(d.scans[k]);
    s.controls.push_back(robot::between(d.reference[k - 1], d.reference[k]));
    std::vector<Pose> before, moved;
    for (std::size_t j = 0; j < kParticles; ++j) {
      Rng rng({2, k, j, purpose::kInitial});
      const Vec<3> xi = rng.normal_vector<3>();
      before.push_back(d.reference[k - 1] + Vec<3>(0.1 * xi(0), 0.1 * xi(1), 0.05 * xi(2)));
      moved.push_back(motion.sample(before.back(), s.controls.back(), rng));
    }
    s.before.push_back(std::move(before));
    s.moved.push_back(std::move(moved));
  }
  return s;
}

const Scene& scene() {
  static const Scene s = make_scene();
  return s;
}

robot::LikelihoodFieldParams params(Interpolation mode) {
  robot::LikelihoodFieldParams p;
  p.max_beams = kBeams;
  p.interpolation = mode;
  return p;
}

template <typename Model>
std::vector<robot::PreparedScan> prepare_all(const Model& model) {
  std::vector<robot::PreparedScan> z;
  for (const robot::LaserScan& scan : scene().scans) z.push_back(model.prepare(scan, "scan"));
  return z;
}

double mean_beams(const std::vector<robot::PreparedScan>& z) {
  double sum = 0.0;
  for (const robot::PreparedScan& p : z) sum += static_cast<double>(p.size());
  return sum / static_cast<double>(z.size());
}

/// Calls f(update, particle) for every particle of every update once per iteration (so that
/// every benchmark sees the same work), and reports the CPU time per particle.
template <typename F>
void every_particle(benchmark::State& state, F&& f) {
  for (auto _ : state)
    for (std::size_t k = 0; k < kUpdates; ++k)
      for (std::size_t j = 0; j < kParticles; ++j) f(k, j);
  state.counters["per_particle"] = benchmark::Counter(
      static_cast<double>(kUpdates * kParticles),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

template <typename Model>
void log_likelihood(benchmark::State& state, Interpolation mode) {
  const Scene& s = scene();
  const Model model(s.field, params(mode), s.mount);
  const std::vector<robot::PreparedScan> z = prepare_all(model);
  double sink = 0.0;
  every_particle(state, [&](std::size_t k, std::size_t j) {
    sink += model.log_likelihood(z[k], s.moved[k][j]);
  });
  benchmark::DoNotOptimize(sink);
  state.counters["beams"] = mean_beams(z);
  state.SetLabel(s.label);
}

template <typename Model>
void negative_log_likelihood(benchmark::State& state) {
  const Scene& s = scene();
  const Model model(s.field, params(Interpolation::kBicubic), s.mount);
  const std::vector<robot::PreparedScan> z = prepare_all(model);
  double sink = 0.0;
  every_particle(state, [&](std::size_t k, std::size_t j) {
    Vec<3> g = Vec<3>::Zero();
    robot::Mat3 h = robot::Mat3::Zero();
    sink += model.negative_log_likelihood(z[k], s.moved[k][j], &g, &h);
    benchmark::DoNotOptimize(g);
    benchmark::DoNotOptimize(h);
  });
  benchmark::DoNotOptimize(sink);
  state.counters["beams"] = mean_beams(z);
  state.SetLabel(s.label);
}

/// One update of a 1000-particle filter at each of the updates per iteration (the particles
/// reset, untimed, before each), on one thread.
template <typename Model, typename Proposal>
void filter_update(benchmark::State& state, Interpolation mode) {
  const Scene& s = scene();
  ThreadLimit limit(1);
  filter::FilterOptions o;
  o.particles = kParticles;
  o.seed = 1;
  filter::MonteCarloLocalization pf(robot::OdometryModel(kAlphas),
                                    Model(s.field, params(mode), s.mount), Proposal{}, o);
  const std::vector<robot::PreparedScan> z = prepare_all(pf.observation());
  const std::vector<double> equal(kParticles, 0.0);
  double evaluations = 0.0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kUpdates; ++k) {
      state.PauseTiming();
      pf.initialize(s.before[k], equal);
      state.ResumeTiming();
      const filter::StepSummary& summary = pf.step_prepared(s.controls[k], z[k]);
      evaluations += summary.newton_evaluations;
      benchmark::DoNotOptimize(summary.mean);
    }
  }
  state.counters["per_particle"] = benchmark::Counter(
      static_cast<double>(kUpdates * kParticles),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["evaluations"] = evaluations / static_cast<double>(state.iterations() * kUpdates);
  state.SetLabel(s.label);
}

/// The beam model (ray casting per beam, the second laser model) on the same particles and scans,
/// for comparison with the likelihood field: its cost grows with the length of the rays.
void beam_log_likelihood(benchmark::State& state) {
  const Scene& s = scene();
  robot::BeamModelParams p;
  p.max_beams = kBeams;
  const robot::BeamModel model(std::make_shared<const robot::OccupancyGrid>(s.map), p, s.mount);
  std::vector<robot::PreparedBeams> z;
  for (const robot::LaserScan& scan : s.scans) z.push_back(model.prepare(scan, "scan"));
  double sink = 0.0, beams = 0.0;
  for (const robot::PreparedBeams& b : z) beams += static_cast<double>(b.size());
  every_particle(state, [&](std::size_t k, std::size_t j) {
    sink += model.log_likelihood(z[k], s.moved[k][j]);
  });
  benchmark::DoNotOptimize(sink);
  state.counters["beams"] = beams / static_cast<double>(z.size());
  state.SetLabel(s.label);
}

/// The one-time cost of nearest-cell interpolation: a new model's first prepare() tabulates the
/// beam density over every cell of the field (padded Intel map: 2127 x 2056 cells).
void nearest_table(benchmark::State& state) {
  const Scene& s = scene();
  for (auto _ : state) {
    const robot::LikelihoodFieldModel model(s.field, params(Interpolation::kNearest), s.mount);
    benchmark::DoNotOptimize(model.prepare(s.scans[0], "scan").cell_log_density);
  }
  state.SetLabel(s.label);
}

/// The largest difference between the current model and the baseline over every particle, for
/// log p and (bicubic) -log p with its derivatives; false when one exceeds what rounding allows.
bool check_agreement() {
  const Scene& s = scene();
  bool ok = true;
  auto report = [&](const char* what, double diff, double allowed) {
    std::fprintf(stderr, "check %-28s max |current - baseline| = %.3g (allowed %.3g)\n", what, diff,
                 allowed);
    ok = ok && diff <= allowed;
  };
  for (Interpolation mode :
       {Interpolation::kNearest, Interpolation::kBilinear, Interpolation::kBicubic}) {
    const robot::LikelihoodFieldModel current(s.field, params(mode), s.mount);
    const baseline::Model before(s.field, params(mode), s.mount);
    const std::vector<robot::PreparedScan> z = prepare_all(current);
    double diff = 0.0, allowed = 0.0;
    for (std::size_t k = 0; k < kUpdates; ++k) {
      // Nearest: each beam's log density may be stored as a float, whose rounding is at most
      // 2^-24 of the largest magnitude, |log(z_rand / z_max)| (the density is at least that),
      // per beam. Interpolated modes: double rounding only, a few ulp of the terms (< 100).
      const double per_beam = mode == Interpolation::kNearest
                                  ? std::ldexp(std::abs(std::log(z[k].rand_density)), -24)
                                  : 1e-12;
      allowed = std::max(allowed, per_beam * static_cast<double>(z[k].size()));
      for (const Pose& x : s.moved[k])
        diff = std::max(diff,
                        std::abs(current.log_likelihood(z[k], x) - before.log_likelihood(z[k], x)));
    }
    const char* names[] = {"log p, nearest", "log p, bilinear", "log p, bicubic"};
    report(names[static_cast<int>(mode)], diff, allowed);
    if (mode != Interpolation::kBicubic) continue;
    double diff_g = 0.0, diff_h = 0.0, scale = 0.0;
    for (std::size_t k = 0; k < kUpdates; ++k)
      for (const Pose& x : s.moved[k]) {
        Vec<3> g1 = Vec<3>::Zero(), g0 = Vec<3>::Zero();
        robot::Mat3 h1 = robot::Mat3::Zero(), h0 = robot::Mat3::Zero();
        current.negative_log_likelihood(z[k], x, &g1, &h1);
        before.negative_log_likelihood(z[k], x, &g0, &h0);
        diff_g = std::max(diff_g, (g1 - g0).cwiseAbs().maxCoeff());
        diff_h = std::max(diff_h, (h1 - h0).cwiseAbs().maxCoeff());
        scale = std::max(scale, h0.cwiseAbs().maxCoeff());
      }
    // The same terms summed in another order: relative rounding of the largest entry.
    report("gradient, bicubic", diff_g, 1e-12 * scale);
    report("Gauss-Newton, bicubic", diff_h, 1e-12 * scale);
  }
  return ok;
}

/// Registers fn(state, args...) under `name`, timed per iteration in milliseconds (a sweep).
template <typename F, typename... Args>
void add(const std::string& name, F fn, Args... args) {
  benchmark::RegisterBenchmark(name.c_str(), fn, args...)->Unit(benchmark::kMillisecond);
}

void register_all() {
  using filter::BootstrapProposal;
  using filter::ImplicitProposal;
  using robot::LikelihoodFieldModel;
  const std::pair<Interpolation, std::string> modes[] = {{Interpolation::kNearest, "nearest"},
                                                         {Interpolation::kBilinear, "bilinear"},
                                                         {Interpolation::kBicubic, "bicubic"}};
  for (const auto& [mode, name] : modes) {
    add("LogLikelihood/" + name + "/baseline", log_likelihood<baseline::Model>, mode);
    add("LogLikelihood/" + name + "/current", log_likelihood<LikelihoodFieldModel>, mode);
  }
  add("NegLogLikelihood/bicubic/baseline", negative_log_likelihood<baseline::Model>);
  add("NegLogLikelihood/bicubic/current", negative_log_likelihood<LikelihoodFieldModel>);
  for (const auto& [mode, name] : modes) {
    add("FilterUpdate/bootstrap/" + name + "/baseline",
        filter_update<baseline::Model, BootstrapProposal>, mode);
    add("FilterUpdate/bootstrap/" + name + "/current",
        filter_update<LikelihoodFieldModel, BootstrapProposal>, mode);
  }
  add("FilterUpdate/implicit/bicubic/baseline", filter_update<baseline::Model, ImplicitProposal>,
      Interpolation::kBicubic);
  add("FilterUpdate/implicit/bicubic/current",
      filter_update<LikelihoodFieldModel, ImplicitProposal>, Interpolation::kBicubic);
  add("NearestTable/build/current", nearest_table);
  add("LogLikelihood/beam-model/current", beam_log_likelihood);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (!check_agreement()) {
    std::fprintf(stderr, "the current laser model disagrees with the baseline: not benchmarked\n");
    return 1;
  }
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
