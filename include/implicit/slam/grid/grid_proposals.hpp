#pragma once
// The proposals of grid SLAM (spec §3.13.2), on equal terms: each draws a particle's new pose
// from its previous pose, the odometry increment and the scan seen against the particle's OWN
// map, and returns the log weight increment. slam::GridSlam (grid_slam.hpp) calls them on the
// particle engine; a user's proposal derives from GridProposal and plugs in the same way.
//
//   bootstrap:   x ~ N(f, Sigma1) (odometry motion model), log w += log p(z | x, map)
//   scan-match:  GMapping (Grisetti et al. 2007): x^ ~ N(f, Sigma1), the scan-match mode x* of
//                log p(z | x, map) near x^ (Newton, a proximal term), K = 27 poses
//                x_k on a 3x3x3 stencil around it, tau_k = p(z | x_k) N(x_k; f, Sigma1), x ~
//                N(mean, cov of the tau-weighted x_k), log w += log sum_k tau_k (GMapping's
//                approximate weight)
//   implicit:    Newton (from f and from starts - 1 draws of N(f, Sigma1), the lowest minimum)
//                to the mode mu of F = -log p(z | x, map) - log N(x; f, Sigma1), H = L L^T
//                there, x = mu + L^-T xi, log w += (3/2) log 2pi + |xi|^2 / 2 - F(x) - log det L
//                (core/log_weight.hpp: exact, E[w] = p(z | x', u, map))
//
//   auto proposal = std::make_shared<slam::ImplicitGridProposal>();
//   double lw = proposal->propose(input, previous, rng, next, stats);   // per particle

#include <string_view>

#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/odometry_model.hpp"
#include "implicit/robot/types.hpp"
#include "implicit/slam/grid/scan_match.hpp"

namespace implicit::slam {

/// What a proposal reads for one particle at one step.
struct GridProposalInput {
  const robot::OdometryModel* motion = nullptr;
  robot::OdometryDelta u = robot::OdometryDelta::Zero();  ///< odometry since the last update
  const GridScanModel* scan = nullptr;                    ///< a view of the particle's map
  const ScanMatchBeams* beams = nullptr;                  ///< the scan's beams (shared)
};

/// What a proposal did for one particle (summed by the filter).
struct GridProposalStats {
  int evaluations = 0;    ///< evaluations of the scan likelihood (with or without derivatives)
  bool failed = false;    ///< weight zero (no SPD motion covariance, or a non-finite weight)
  bool fallback = false;  ///< no usable mode: sampled the motion model instead
};

/// A proposal: draws `next` from `previous` and returns the log weight increment (-inf: zero).
/// Called in parallel, one particle per call: it may write only `next` and `stats`, and draws
/// only from `rng` (the particle's keyed stream).
class GridProposal {
 public:
  virtual ~GridProposal() = default;
  virtual std::string_view name() const = 0;
  virtual double propose(const GridProposalInput& in, const robot::Pose& previous, Rng& rng,
                         robot::Pose& next, GridProposalStats& stats) const = 0;
};

class BootstrapGridProposal final : public GridProposal {
 public:
  std::string_view name() const override { return "bootstrap"; }
  double propose(const GridProposalInput& in, const robot::Pose& previous, Rng& rng,
                 robot::Pose& next, GridProposalStats& stats) const override;
};

/// Coarse to fine (Hector SLAM's pyramid, without a second map): Newton first minimises the
/// objective with the scan likelihood smoothed over `coarse_smoothing` cells (a basin twice as
/// wide at 4 against 2), then from there with the model's own smoothing. Only the start of the
/// second Newton changes: the weights are those of the fine objective. 0 (or not above the
/// model's smoothing): off, the default: on the Intel log it costs the implicit proposal more
/// CPU than further starts for less gain (bench_grid_slam, GridSlam/implicit_coarse4).
struct CoarseStartOptions {
  int coarse_smoothing = 0;
  /// Throws InvalidArgument unless 0 <= coarse_smoothing <= ScanMatchParams::kMaxSmoothing.
  void validate() const;
};

struct ScanMatchProposalOptions {
  /// Spacing of the 3x3x3 stencil around the scan-match mode (x [m], y [m], heading [rad]);
  /// (step / 2)^2 is added to the fitted covariance's diagonal so it stays SPD when one pose
  /// dominates.
  Vec<3> step = Vec<3>(0.02, 0.02, 0.01);
  /// Scale of the scan match's proximal term 1/2 |(x - x^) / radius|^2 (x [m], y [m], heading
  /// [rad]): GMapping's hill climbing is local, and Newton on the likelihood alone would slide
  /// along a corridor to wherever a wall fits.
  Vec<3> match_radius = Vec<3>(0.2, 0.2, 0.2);
  CoarseStartOptions coarse;
  /// Throws InvalidArgument unless every step and radius is finite and > 0.
  void validate() const;
};

class ScanMatchGridProposal final : public GridProposal {
 public:
  explicit ScanMatchGridProposal(const ScanMatchProposalOptions& options = {});
  std::string_view name() const override { return "gmapping"; }
  double propose(const GridProposalInput& in, const robot::Pose& previous, Rng& rng,
                 robot::Pose& next, GridProposalStats& stats) const override;

 private:
  ScanMatchProposalOptions options_;
};

struct ImplicitGridOptions {
  CoarseStartOptions coarse;
  /// Newton runs from f and from starts - 1 poses drawn from N(f, Sigma1); the lowest minimum
  /// centres the map. The starts are drawn before x, so the weights stay exact
  /// (filter/observation_proposals.hpp). After a short step with a turn the odometry's heading
  /// can be off by many degrees, beyond the basin around f, and the particles would all find the
  /// same wrong minimum; other starts give them other basins, as GMapping's sampled starts do.
  int starts = 4;
  /// The random map (spec §1.3) instead of the linear one: x = mu + lambda L^-T xi / |xi| with
  /// F(x) = F(mu) + |xi|^2 / 2. Exact where F's level sets are star-shaped about mu; a ray
  /// without a root gives the sample weight zero.
  bool random_map = false;
  /// Throws InvalidArgument naming the field.
  void validate() const;
};

class ImplicitGridProposal final : public GridProposal {
 public:
  explicit ImplicitGridProposal(const ImplicitGridOptions& options = {});
  std::string_view name() const override { return "implicit"; }
  double propose(const GridProposalInput& in, const robot::Pose& previous, Rng& rng,
                 robot::Pose& next, GridProposalStats& stats) const override;

 private:
  ImplicitGridOptions options_;
};

/// F(x) = 1/2 |x - f|^2_{Sigma1^-1} + 1/2 log det(2 pi Sigma1) - log p(z | x, map): the implicit
/// proposal's objective, with the scan model's exact Hessian and Gauss-Newton matrix.
class GridPoseObjective {
 public:
  GridPoseObjective(const GridScanModel& scan, const ScanMatchBeams& beams, const robot::Pose& f,
                    const SmallFactor<3>& sigma1);
  double evaluate(const robot::Pose& x, Vec<3>* gradient, robot::Mat3* hessian,
                  robot::Mat3* gauss_newton) const;
  double evaluate(const robot::Pose& x, Vec<3>* gradient, robot::Mat3* hessian) const {
    return evaluate(x, gradient, hessian, nullptr);
  }
  const robot::Pose& prediction() const { return f_; }

 private:
  const GridScanModel* scan_;
  const ScanMatchBeams* beams_;
  robot::Pose f_;
  robot::Mat3 information_;
  double constant_;
};

/// Newton's rules for the grid objectives: exact Hessian, the Gauss-Newton matrix where it is not
/// SPD (with the prior always SPD), at most 20 iterations (see grid_proposals.cpp for why).
NewtonOptions grid_newton_options();

}  // namespace implicit::slam
