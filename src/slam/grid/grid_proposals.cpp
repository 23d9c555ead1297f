#include "implicit/slam/grid/grid_proposals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/log_weight.hpp"

namespace implicit::slam {

namespace {

constexpr double kGridNegInf = -std::numeric_limits<double>::infinity();

// f, Sigma1 and its factor; false (the particle kept, weight zero) when Sigma1 is not SPD or f
// is not finite.
bool grid_predict(const GridProposalInput& in, const robot::Pose& previous, robot::Pose& f,
                  SmallFactor<3>& sigma1, robot::Pose& next, GridProposalStats& st) {
  robot::Mat3 cov;
  in.motion->predict_with_covariance(previous, in.u, f, cov);
  if (f.allFinite() && cov.allFinite() && sigma1.compute(cov)) return true;
  st.failed = true;
  next = previous;
  return false;
}

// The scan-match objective of the GMapping-style proposal: -log p(z | x, map) plus the proximal
// term 1/2 |(x - start) / radius|^2 that keeps the match local.
struct GridScanMatchObjective {
  const GridScanModel* scan;
  const ScanMatchBeams* beams;
  robot::Pose start;
  Vec<3> precision;  // 1 / radius^2
  double evaluate(const robot::Pose& x, Vec<3>* g, robot::Mat3* h, robot::Mat3* gn) const {
    const Vec<3> d = x - start;
    const Vec<3> pd = precision.cwiseProduct(d);
    if (g) *g = pd;
    if (h) *h = precision.asDiagonal();
    if (gn) *gn = precision.asDiagonal();
    return 0.5 * d.dot(pd) + scan->negative_log_likelihood(*beams, x, g, h, gn);
  }
  double evaluate(const robot::Pose& x, Vec<3>* g, robot::Mat3* h) const {
    return evaluate(x, g, h, nullptr);
  }
};

// log N(x; f, Sigma1) with Sigma1 = L L^T.
double grid_log_motion_density(const robot::Pose& x, const robot::Pose& f,
                               const SmallFactor<3>& sigma1) {
  const Vec<3> eta = sigma1.solve_lower(x - f);
  return gaussian_log_density(3, sigma1.log_det_L(), eta.squaredNorm());
}

// The coarse stage of coarse to fine (CoarseStartOptions): Newton on the objective make(model)
// with the likelihood smoothed over `coarse` cells, from `start`; its minimum, or `start` when it
// has none.
template <typename MakeObjective>
robot::Pose grid_coarse_start(const GridProposalInput& in, int coarse, const robot::Pose& start,
                              MakeObjective make, GridProposalStats& st) {
  if (coarse <= in.scan->params().smoothing) return start;
  ScanMatchParams p = in.scan->params();
  p.smoothing = coarse;
  const GridScanModel model = GridScanModel::unchecked(in.scan->map(), p, in.scan->mount());
  const auto objective = make(model);
  NewtonOptions o = grid_newton_options();
  o.decrement_tolerance = 1e-1;  // a start, not the centre: the fine stage refines it
  o.max_iterations = 10;
  const auto nr = newton_minimize<SmallFactor<3>>(objective, start, o);
  st.evaluations += nr.evaluations;
  return std::isfinite(nr.value) && nr.x.allFinite() ? nr.x : start;
}

}  // namespace

void CoarseStartOptions::validate() const {
  require(coarse_smoothing >= 0 && coarse_smoothing <= ScanMatchParams::kMaxSmoothing,
          "CoarseStartOptions: expected coarse_smoothing in [0, {}] cells, got {}",
          ScanMatchParams::kMaxSmoothing, coarse_smoothing);
}

// An exact Hessian converges quadratically near the mode, so a full step below 1e-5 (m, rad) ends
// Newton (the next would be ~1e-10); a decrement g^T H^-1 g below 1e-3 is a centre within about
// 5e-4 of F's minimum, a variance of 1e-3 added to the log weights (far below the spread of
// |xi|^2 / 2, 3/2 in three dimensions). 20 iterations at most: where Newton stops does not bias
// the weights, it only lowers the effective sample size. Without damping: the Gauss-Newton matrix
// plus the prior's information is always SPD.
NewtonOptions grid_newton_options() {
  NewtonOptions o;
  o.max_iterations = 20;
  o.gradient_tolerance = 0.0;
  o.step_tolerance = 1e-7;
  o.relative_step_tolerance = false;
  o.decrement_tolerance = 1e-3;
  o.final_step = 1e-5;
  o.armijo = 1e-4;
  o.max_backtracks = 30;
  o.fallback = HessianFallback::kGaussNewton;
  o.damping = false;
  return o;
}

GridPoseObjective::GridPoseObjective(const GridScanModel& scan, const ScanMatchBeams& beams,
                                     const robot::Pose& f, const SmallFactor<3>& sigma1)
    : scan_(&scan),
      beams_(&beams),
      f_(f),
      information_(sigma1.inverse()),
      constant_(gaussian_log_normaliser(3, sigma1.log_det_L())) {}

double GridPoseObjective::evaluate(const robot::Pose& x, Vec<3>* gradient, robot::Mat3* hessian,
                                   robot::Mat3* gauss_newton) const {
  const Vec<3> d = x - f_;
  const Vec<3> pd = information_ * d;
  if (gradient) *gradient = pd;
  if (hessian) *hessian = information_;
  if (gauss_newton) *gauss_newton = information_;
  return constant_ + 0.5 * d.dot(pd) +
         scan_->negative_log_likelihood(*beams_, x, gradient, hessian, gauss_newton);
}

double BootstrapGridProposal::propose(const GridProposalInput& in, const robot::Pose& previous,
                                      Rng& rng, robot::Pose& next, GridProposalStats& st) const {
  robot::Pose f;
  SmallFactor<3> sigma1;
  if (!grid_predict(in, previous, f, sigma1, next, st)) return kGridNegInf;
  const Vec<3> xi = rng.normal_vector<3>();
  next = f + sigma1.matrixL() * xi;
  ++st.evaluations;
  const double lw = in.scan->log_likelihood(*in.beams, next);
  if (!std::isfinite(lw)) {
    st.failed = true;
    return kGridNegInf;
  }
  return lw;
}

void ScanMatchProposalOptions::validate() const {
  require(step.allFinite() && (step.array() > 0).all(),
          "ScanMatchProposalOptions: expected step (x [m], y [m], heading [rad]) finite and > 0, "
          "got ({}, {}, {})",
          step(0), step(1), step(2));
  coarse.validate();
  require(match_radius.allFinite() && (match_radius.array() > 0).all(),
          "ScanMatchProposalOptions: expected match_radius (x [m], y [m], heading [rad]) finite "
          "and > 0, got ({}, {}, {})",
          match_radius(0), match_radius(1), match_radius(2));
}

ScanMatchGridProposal::ScanMatchGridProposal(const ScanMatchProposalOptions& options)
    : options_(options) {
  options_.validate();
}

double ScanMatchGridProposal::propose(const GridProposalInput& in, const robot::Pose& previous,
                                      Rng& rng, robot::Pose& next, GridProposalStats& st) const {
  robot::Pose f;
  SmallFactor<3> sigma1;
  if (!grid_predict(in, previous, f, sigma1, next, st)) return kGridNegInf;
  const Vec<3> eta = rng.normal_vector<3>();
  const Vec<3> xi = rng.normal_vector<3>();
  const robot::Pose start = f + sigma1.matrixL() * eta;
  // The scan-match mode near the motion sample (the proximal term's matrix is SPD, so the
  // Gauss-Newton fallback always factors).
  const Vec<3> precision = options_.match_radius.cwiseAbs2().cwiseInverse();
  const robot::Pose begin = grid_coarse_start(
      in, options_.coarse.coarse_smoothing, start,
      [&](const GridScanModel& coarse) {
        return GridScanMatchObjective{&coarse, in.beams, start, precision};
      },
      st);
  const GridScanMatchObjective match{in.scan, in.beams, start, precision};
  const auto nr = newton_minimize<SmallFactor<3>>(match, begin, grid_newton_options());
  st.evaluations += nr.evaluations;
  robot::Pose mode = start;
  if (std::isfinite(nr.value) && nr.x.allFinite())
    mode = nr.x;
  else
    st.fallback = true;
  // tau_k = p(z | x_k) N(x_k; f, Sigma1) on the stencil; its weighted mean and covariance.
  constexpr int kStencil = 27;
  std::array<robot::Pose, kStencil> xs;
  std::array<double, kStencil> log_tau;
  for (int k = 0; k < kStencil; ++k) {
    const Vec<3> offset((k % 3) - 1, ((k / 3) % 3) - 1, (k / 9) - 1);
    const auto kk = static_cast<std::size_t>(k);
    xs[kk] = mode + offset.cwiseProduct(options_.step);
    log_tau[kk] =
        in.scan->log_likelihood(*in.beams, xs[kk]) + grid_log_motion_density(xs[kk], f, sigma1);
  }
  st.evaluations += kStencil;
  const double top = *std::max_element(log_tau.begin(), log_tau.end());
  if (!std::isfinite(top)) {
    st.failed = true;
    next = mode;
    return kGridNegInf;
  }
  double sum = 0.0;
  Vec<3> mean = Vec<3>::Zero();
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const double t = std::exp(log_tau[k] - top);
    sum += t;
    mean += t * xs[k];
  }
  mean /= sum;
  robot::Mat3 cov = (0.25 * options_.step.cwiseAbs2()).asDiagonal();
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const Vec<3> d = xs[k] - mean;
    cov += (std::exp(log_tau[k] - top) / sum) * d * d.transpose();
  }
  SmallFactor<3> fit;
  if (!fit.compute(cov)) {
    st.failed = true;
    next = mode;
    return kGridNegInf;
  }
  next = mean + fit.matrixL() * xi;
  return top + std::log(sum);
}

void ImplicitGridOptions::validate() const {
  coarse.validate();
  require(starts >= 1 && starts <= 64, "ImplicitGridOptions: expected starts in [1, 64], got {}",
          starts);
}

ImplicitGridProposal::ImplicitGridProposal(const ImplicitGridOptions& options) : options_(options) {
  options_.validate();
}

double ImplicitGridProposal::propose(const GridProposalInput& in, const robot::Pose& previous,
                                     Rng& rng, robot::Pose& next, GridProposalStats& st) const {
  robot::Pose f;
  SmallFactor<3> sigma1;
  if (!grid_predict(in, previous, f, sigma1, next, st)) return kGridNegInf;
  const Vec<3> xi = rng.normal_vector<3>();
  const GridPoseObjective obj(*in.scan, *in.beams, f, sigma1);
  NewtonMinimum<SmallFactor<3>> nr;
  for (int k = 0; k < options_.starts; ++k) {
    robot::Pose start = f;
    if (k > 0) {
      const Vec<3> eta = rng.normal_vector<3>();
      start = f + sigma1.matrixL() * eta;
    }
    const robot::Pose begin = grid_coarse_start(
        in, options_.coarse.coarse_smoothing, start,
        [&](const GridScanModel& coarse) {
          return GridPoseObjective(coarse, *in.beams, f, sigma1);
        },
        st);
    auto other = newton_minimize<SmallFactor<3>>(obj, begin, grid_newton_options());
    st.evaluations += other.evaluations;
    if (k == 0 || (other.factor_ok && std::isfinite(other.value) &&
                   (!nr.factor_ok || !std::isfinite(nr.value) || other.value < nr.value)))
      nr = std::move(other);
  }
  ++st.evaluations;  // F at the sample
  st.fallback = st.fallback || !nr.exact_factor;
  const bool usable = nr.factor_ok && nr.status != MinimizeStatus::kNonFinite &&
                      std::isfinite(nr.value) && std::isfinite(nr.factor.log_det_L());
  if (!usable) {  // no Gaussian approximation: the bootstrap step, still a valid proposal
    st.fallback = true;
    next = f + sigma1.matrixL() * xi;
    const double lw = in.scan->log_likelihood(*in.beams, next);
    if (!std::isfinite(lw)) {
      st.failed = true;
      return kGridNegInf;
    }
    return lw;
  }
  double lw = -std::numeric_limits<double>::infinity();
  if (!options_.random_map)
    lw = linear_map(obj, nr.x, nr.factor, xi, next);
  else if (implicit::random_map(obj, nr.x, nr.value, nr.factor, xi, next, lw) != RayStatus::kOk)
    next = nr.x;  // no root on the ray: weight zero
  if (!std::isfinite(lw)) {
    st.failed = true;
    return kGridNegInf;
  }
  return lw;
}

}  // namespace implicit::slam
