#include "implicit/slam/grid/grid_slam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"

namespace implicit::slam {

void GridSlamOptions::validate() const {
  require(particles >= 1 && particles <= (std::size_t{1} << 24),
          "GridSlamOptions: expected particles in [1, 2^24], got {}", particles);
  require(std::isfinite(resample_threshold) && resample_threshold >= 0 && resample_threshold <= 1,
          "GridSlamOptions: expected resample_threshold in [0, 1], got {}", resample_threshold);
  map.validate();
  scan.validate();
  gate.validate();
  alphas.validate();
  require(floor_std.allFinite() && (floor_std.array() > 0).all(),
          "GridSlamOptions: expected floor_std finite and > 0, got ({}, {}, {})", floor_std(0),
          floor_std(1), floor_std(2));
  require(std::isfinite(mount.x) && std::isfinite(mount.y) && std::isfinite(mount.yaw),
          "GridSlamOptions: expected a finite mount, got ({}, {}, {})", mount.x, mount.y,
          mount.yaw);
}

GridSlam::GridSlam(const GridSlamOptions& options, std::shared_ptr<const GridProposal> proposal)
    : options_(options), proposal_(std::move(proposal)), motion_([&] {
        options.validate();
        return robot::OdometryModel(options.alphas, options.floor_std);
      }()) {
  require(proposal_ != nullptr, "GridSlam: expected a proposal, got none (null)");
}

void GridSlam::initialize(const robot::Pose& x0, const robot::Pose& odometry,
                          const robot::LaserScan& scan) {
  require(x0.allFinite(), "GridSlam::initialize: expected a finite initial pose, got ({}, {}, {})",
          x0(0), x0(1), x0(2));
  require(odometry.allFinite(),
          "GridSlam::initialize: expected a finite odometry pose, got ({}, {}, {})", odometry(0),
          odometry(1), odometry(2));
  GridSlamParticle p;
  p.pose = x0;
  p.map = TiledLogOddsGrid(options_.map);
  p.map.integrate(x0, options_.mount, scan);  // validates the scan
  p.node = 0;
  engine_.assign(options_.particles, p);  // every copy shares the first scan's tiles
  nodes_.clear();
  nodes_.push_back({x0, scan.time, 0});
  stats_.assign(options_.particles, GridProposalStats{});
  last_odometry_ = odometry;
  steps_ = 0;
  calls_ = 0;
  best_ = 0;
  initialized_ = true;
}

GridSlamStep GridSlam::step(const robot::Pose& odometry, const robot::LaserScan& scan) {
  require(initialized_, "GridSlam::step: initialize() first");
  require(odometry.allFinite(), "GridSlam::step: expected a finite odometry pose, got ({}, {}, {})",
          odometry(0), odometry(1), odometry(2));
  const std::string where = "GridSlam::step: scan " + std::to_string(calls_ + 1);
  scan.validate(where);
  ++calls_;  // scans accepted since initialize(), processed or not
  GridSlamStep r;
  if (!options_.gate.due(last_odometry_, odometry)) return r;
  r.processed = true;
  const robot::OdometryDelta u = robot::between(last_odometry_, odometry);
  const GridScanModel shared =
      GridScanModel::unchecked(engine_.particles()[0].map, options_.scan, options_.mount);
  shared.prepare_into(scan, where, beams_);
  const std::size_t m = engine_.size();
  const std::size_t base = nodes_.size();
  require(base + m < std::numeric_limits<std::uint32_t>::max(),
          "GridSlam::step: more than 2^32 trajectory nodes");
  nodes_.resize(base + m);
  ++steps_;
  const std::uint64_t n = steps_;
  engine_.move(
      [&](std::size_t j, GridSlamParticle& p) {
        const GridScanModel model = GridScanModel::unchecked(p.map, options_.scan, options_.mount);
        const GridProposalInput in{&motion_, u, &model, &beams_};
        GridProposalStats& st = stats_[j];
        st = GridProposalStats{};
        Rng rng({.seed = options_.seed, .step = n, .index = j, .purpose = purpose::kProposal});
        robot::Pose next;
        const double lw = proposal_->propose(in, p.pose, rng, next, st);
        nodes_[base + j] = {next, scan.time, p.node};
        p.pose = next;
        p.node = static_cast<std::uint32_t>(base + j);
        return lw;
      },
      1);  // a particle's proposal is heavy enough to be a task of its own
  const filter::Reweighting rw = engine_.reweight();
  r.ess = rw.ess;
  r.log_likelihood_increment = rw.log_likelihood_increment;
  r.all_weights_zero = rw.all_weights_zero;
  double evaluations = 0.0;
  for (const GridProposalStats& st : stats_) {
    r.failures += st.failed;
    r.fallbacks += st.fallback;
    evaluations += st.evaluations;
  }
  r.mean_evaluations = evaluations / static_cast<double>(m);
  const auto w = engine_.weights();
  best_ = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
  if (needs_resampling(rw.ess, m, options_.resample_threshold)) {
    Rng rng({.seed = options_.seed, .step = n, .purpose = purpose::kResampling});
    uniforms_.resize(uniforms_needed(ResamplingScheme::kSystematic, m));
    for (double& v : uniforms_) v = rng.uniform();
    resample(ResamplingScheme::kSystematic, w, uniforms_, m, ancestors_);
    const std::size_t best_before = best_;
    engine_.resample(ancestors_);
    // Nothing reads the old population, and its references would make every map write below
    // copy its tile.
    engine_.release_before_resampling();
    best_ = static_cast<std::size_t>(std::find(ancestors_.begin(), ancestors_.end(), best_before) -
                                     ancestors_.begin());
    if (best_ == m) best_ = 0;  // systematic resampling keeps the largest weight's particle
    r.resampled = true;
  }
  auto ps = engine_.particles();
  parallel_for(
      m, [&](std::size_t j) { ps[j].map.integrate(ps[j].pose, options_.mount, scan); }, 1);
  last_odometry_ = odometry;
  return r;
}

std::vector<GridSlamPose> GridSlam::trajectory(std::size_t particle) const {
  require(initialized_ && particle < engine_.size(),
          "GridSlam::trajectory: expected a particle below {}, got {}", engine_.size(), particle);
  std::vector<GridSlamPose> out;
  std::uint32_t k = engine_.particles()[particle].node;
  for (;;) {
    out.push_back({nodes_[k].time, nodes_[k].pose});
    if (nodes_[k].parent == k) break;
    k = nodes_[k].parent;
  }
  std::reverse(out.begin(), out.end());
  return out;
}

std::vector<GridSlamPose> GridSlam::best_trajectory() const { return trajectory(best_); }

}  // namespace implicit::slam
