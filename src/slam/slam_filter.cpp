// EKF-SLAM, FastSLAM 1.0/2.0 and implicit SLAM (A)/(B) behind the SlamFilter interface.
#include "implicit/slam/slam_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian_factor.hpp"
#include "implicit/core/implicit_maps.hpp"
#include "implicit/core/newton.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/resampling.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/filter/particle_engine.hpp"
#include "implicit/filter/pose_moments.hpp"
#include "implicit/robot/data_association.hpp"
#include "implicit/slam/ekf_slam.hpp"
#include "implicit/slam/landmark_index.hpp"
#include "implicit/slam/landmark_map.hpp"
#include "implicit/slam/pose_proposals.hpp"
#include "implicit/slam/proposals.hpp"

namespace implicit::slam {

using robot::RangeBearingSensor;

namespace {

KnownLandmark known_landmark(std::size_t slot, const Measurement& z, const LandmarkEstimate& l) {
  KnownLandmark k;
  k.slot = slot;
  k.z = z;
  k.mean = l.mean;
  k.cov = l.cov;
  return k;
}

void check_observation(std::uint64_t n, const Observation& o) {
  require(std::isfinite(o.z(0)) && std::isfinite(o.z(1)),
          "SLAM step {}: expected a finite observation, got (range {}, bearing {})", n, o.z(0),
          o.z(1));
  require(o.z(0) > 0.0, "SLAM step {}: expected a positive range, got {}", n, o.z(0));
}

Mat23 inverse_jacobian_pose(const Pose& x, const Measurement& z) {
  const double angle = x(2) + z(1) - kPi / 2.0;
  Mat23 g;
  g << 1.0, 0.0, -z(0) * std::sin(angle), 0.0, 1.0, z(0) * std::cos(angle);
  return g;
}

/// The filter's motion model: options.model, else the Ute with options.motion.
robot::AnyMotionModel motion_model(const SlamOptions& o) {
  if (o.model) return *o.model;
  return robot::UteModel(o.motion);
}

/// The model for a step of length dt (the nominal one itself when dt is nominal).
robot::AnyMotionModel step_model(const robot::AnyMotionModel& base, double dt) {
  require(dt > 0 && std::isfinite(dt), "SLAM: expected a positive step length, got {}", dt);
  return dt == base.dt() ? base : base.with_dt(dt);
}

// ------------------------------------------------------------------------------------------
class EkfSlamFilter final : public SlamFilter {
 public:
  EkfSlamFilter(const SlamOptions& opt, const Pose& x0)
      : opt_(opt), base_(motion_model(opt)), model_(base_), core_(x0, Mat<3>::Zero()) {}

  void set_step_length(double dt) override { model_ = step_model(base_, dt); }

  void set_known_map(std::span<const Landmark> landmarks) override {
    require(core_.landmark_count() == 0 && stats_.steps == 0,
            "EKF-SLAM: set_known_map must be called before the first step");
    for (std::size_t k = 0; k < landmarks.size(); ++k) {
      core_.augment(landmarks[k], Mat23::Zero(), Mat<2>::Zero());
      id_of_slot_.push_back(static_cast<int>(k));
      slot_of_id_[static_cast<int>(k)] = static_cast<int>(k);
    }
  }

  void step(std::uint64_t n, const Control& u, std::span<const Observation> obs) override {
    require(u.allFinite(), "SLAM step {}: expected a finite control, got ({}, {})", n, u(0), u(1));
    for (const auto& o : obs) check_observation(n, o);
    const Pose x = core_.pose();
    core_.predict(model_.predict(x, u), model_.jacobian_state(x, u),
                  model_.process_covariance(x, u));
    ++stats_.steps;
    const RangeBearingSensor& s = opt_.sensor;
    const Mat<2>& r = s.noise_covariance();
    for (const Observation& o : obs) {
      if (o.z(0) < opt_.min_range) {
        ++stats_.skipped;
        continue;
      }
      const Pose xp = core_.pose();
      int slot = -1;
      if (opt_.association == Association::kKnown) {
        require(o.landmark >= 0, "SLAM step {}: known association needs a landmark id, got {}", n,
                o.landmark);
        if (const auto it = slot_of_id_.find(o.landmark); it != slot_of_id_.end())
          slot = it->second;
      } else {
        // One shared ML rule (robot/data_association.hpp): min d^2 + log det S inside the gate.
        slot = robot::associate_max_likelihood(
                   core_.landmark_count(),
                   [&](int k, Measurement& e, Mat<2>& sk) {
                     const Landmark m = core_.landmark(k);
                     e = RangeBearingSensor::residual(s.predict(xp, m), o.z);
                     sk = core_.innovation_covariance(k, s.jacobian_pose(xp, m),
                                                      s.jacobian_landmark(xp, m), r);
                     return true;
                   },
                   opt_.gate_chi2)
                   .index;
      }
      if (slot < 0) {
        const Landmark m = RangeBearingSensor::inverse(xp, o.z);
        const Mat<2> gz = RangeBearingSensor::inverse_jacobian_measurement(xp, o.z);
        slot = core_.augment(m, inverse_jacobian_pose(xp, o.z), gz * r * gz.transpose());
        id_of_slot_.push_back(o.landmark);
        if (opt_.association == Association::kKnown) slot_of_id_[o.landmark] = slot;
        ++stats_.new_landmarks;
        continue;
      }
      const Landmark m = core_.landmark(slot);
      const Measurement nu = -RangeBearingSensor::residual(s.predict(xp, m), o.z);
      if (core_.update(slot, nu, s.jacobian_pose(xp, m), s.jacobian_landmark(xp, m), r))
        ++stats_.updates;
      else
        ++stats_.skipped;
    }
  }

  PoseEstimate pose() const override { return {core_.pose(), core_.pose_covariance()}; }
  MapEstimate map() const override {
    MapEstimate m;
    for (int k = 0; k < core_.landmark_count(); ++k) {
      m.landmarks.push_back(core_.landmark(k));
      m.ids.push_back(id_of_slot_[static_cast<std::size_t>(k)]);
    }
    return m;
  }
  const SlamStats& stats() const override { return stats_; }
  std::size_t map_bytes() const override {
    const auto n = static_cast<std::size_t>(core_.mean().size());
    return sizeof(double) * (n + n * n);
  }
  const EkfSlamCore& core() const { return core_; }

 private:
  SlamOptions opt_;
  robot::AnyMotionModel base_;   ///< the model at its nominal step
  robot::AnyMotionModel model_;  ///< the model for the current step length
  EkfSlamCore core_;
  // Known association: the slot of each landmark id. A hash map, not a table indexed by id: ids
  // are any int in [0, 2^31 - 1], and a table up to the largest would take 8 GiB.
  std::unordered_map<int, int> slot_of_id_;
  std::vector<int> id_of_slot_;
  SlamStats stats_;
};

// ------------------------------------------------------------------------------------------
/// A particle of particle SLAM: a pose and its own (copy-on-write) landmark map.
struct Particle {
  Pose x = Pose::Zero();
  LandmarkEstimates map;
};

struct ParticleOutcome {
  int newton_iterations = 0;
  int newton_solves = 0;
  int newton_not_converged = 0;
  int new_landmarks = 0;
  int updates = 0;
  std::size_t known_over_limit = 0;  ///< known landmarks seen beyond the proposal's capacity
  /// Landmarks written this step that the association index must (re-)register.
  std::vector<std::pair<std::uint32_t, LandmarkEstimate>> moved;

  void reset() {
    newton_iterations = newton_solves = newton_not_converged = new_landmarks = updates = 0;
    known_over_limit = 0;
    moved.clear();  // keeps its capacity: no allocation per particle and step
  }
};

// Below this map size the linear scan (with its exact range check) is as fast or faster than the
// grid look-ups: measured 3.5x faster on Victoria Park at 400-700 landmarks, 2-3x slower on the
// dense synthetic field at 1 000 (docs/performance.md). Both give the same association.
constexpr std::size_t kIndexedAssociationMinLandmarks = 1024;

class ParticleSlamFilter final : public SlamFilter {
 public:
  ParticleSlamFilter(const SlamOptions& opt, const Pose& x0, AnyPoseProposal proposal)
      : opt_(opt),
        base_(motion_model(opt)),
        model_(base_),
        m_(static_cast<std::size_t>(opt.particles)),
        engine_(m_, Particle{x0, {}}),
        proposal_(std::move(proposal)),
        point_landmarks_(proposal_.point_landmarks()) {
    outcome_.resize(m_);
    estimate_.mean = x0;
  }

  void set_step_length(double dt) override { model_ = step_model(base_, dt); }

  void set_known_map(std::span<const Landmark> landmarks) override {
    require(stats_.steps == 0 && engine_.particles()[0].map.empty(),
            "particle SLAM: set_known_map must be called before the first step");
    LandmarkEstimates map;
    for (std::size_t k = 0; k < landmarks.size(); ++k) {
      map.push_back({landmarks[k], Mat<2>::Zero()});
      index_.insert(static_cast<std::uint32_t>(k), landmarks[k], 0.0);
      slot_of_id_[static_cast<int>(k)] = static_cast<int>(k);
      id_of_slot_.push_back(static_cast<int>(k));
    }
    for (auto& p : engine_.particles()) p.map = map;
  }

  void step(std::uint64_t n, const Control& u, std::span<const Observation> obs) override {
    require(u.allFinite(), "SLAM step {}: expected a finite control, got ({}, {})", n, u(0), u(1));
    for (const auto& o : obs) check_observation(n, o);
    ++stats_.steps;
    // Known association: "new or known" is decided once for all particles (they share slots).
    slots_.assign(obs.size(), -1);
    use_.assign(obs.size(), 1);
    const std::size_t slots_before = id_of_slot_.size();
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (obs[i].z(0) < opt_.min_range) {
        use_[i] = 0;
        ++stats_.skipped;
        continue;
      }
      if (opt_.association != Association::kKnown) continue;
      require(obs[i].landmark >= 0, "SLAM step {}: known association needs a landmark id, got {}",
              n, obs[i].landmark);
      const auto [it, added] =
          slot_of_id_.try_emplace(obs[i].landmark, static_cast<int>(id_of_slot_.size()));
      if (added) {
        id_of_slot_.push_back(obs[i].landmark);
        slots_[i] = it->second;
      } else if (static_cast<std::size_t>(it->second) < slots_before) {
        slots_[i] = it->second;
      } else {
        use_[i] = 0;  // a second detection of a landmark created in this same step
        ++stats_.skipped;
      }
    }
    const bool weighted = std::any_of(use_.begin(), use_.end(), [](int v) { return v != 0; });
    engine_.move(
        [&](std::size_t j, Particle& p) { return step_particle(j, p, n, u, obs, slots_before); },
        8);
    const bool ml = opt_.association == Association::kMaximumLikelihood;
    std::size_t over_limit = 0;
    for (const auto& oc : outcome_) {
      if (ml) {
        // Sequential, after the parallel particle loop: the index is shared.
        for (const auto& [slot, l] : oc.moved) {
          index_.insert(slot, l.mean, l.cov.trace());  // no-op when already registered there
          cov_trace_bound_ = std::max(cov_trace_bound_, l.cov.trace());
        }
      }
      stats_.newton_iterations += static_cast<std::size_t>(oc.newton_iterations);
      stats_.newton_solves += static_cast<std::size_t>(oc.newton_solves);
      stats_.newton_not_converged += static_cast<std::size_t>(oc.newton_not_converged);
      over_limit = std::max(over_limit, oc.known_over_limit);
    }
    require(over_limit == 0,
            "SLAM step {}: a particle sees {} known landmarks, more than the {} per step its "
            "proposal takes (thin the detections, e.g. with a larger --min-range, or use another "
            "method)",
            n, over_limit, proposal_.max_known_landmarks());
    if (opt_.association == Association::kKnown) {
      for (std::size_t i = 0; i < obs.size(); ++i)
        if (use_[i] != 0) {
          if (static_cast<std::size_t>(slots_[i]) >= slots_before)
            ++stats_.new_landmarks;
          else
            ++stats_.updates;
        }
    }
    // Weights: normalise in the log domain, estimate, resample.
    const filter::Reweighting ws = engine_.reweight();
    if (ws.all_weights_zero) ++stats_.degenerate_steps;
    const std::span<const double> w = engine_.weights();
    const auto best = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
    if (opt_.association != Association::kKnown) {
      stats_.new_landmarks += static_cast<std::size_t>(outcome_[best].new_landmarks);
      stats_.updates += static_cast<std::size_t>(outcome_[best].updates);
    }
    compute_estimate();
    if (weighted) {
      ++stats_.weighted_steps;
      stats_.ess_fraction_sum += ws.ess / static_cast<double>(m_);
    }
    if (needs_resampling(ws.ess, m_, opt_.resample_threshold)) {
      // The map estimate, like the pose estimate, uses the weights of this step BEFORE
      // resampling (spec §4): resampling only adds Monte Carlo noise to a weighted mean. The
      // engine keeps the old population until the next move (its maps are shared: free).
      Rng rng({opt_.seed, n, 0, purpose::kResampling});
      engine_.resample(resample(ResamplingScheme::kSystematic, w, m_, rng));
      ++stats_.resamplings;
    }
  }

  PoseEstimate pose() const override { return estimate_; }

  MapEstimate map() const override {
    MapEstimate out;
    const bool before = engine_.resampled();
    const std::span<const Particle> particles =
        before ? engine_.before_resampling() : engine_.particles();
    const std::span<const double> w =
        before ? engine_.weights_before_resampling() : engine_.weights();
    if (opt_.association == Association::kKnown) {
      const std::size_t k = particles[0].map.size();
      out.landmarks.assign(k, Landmark::Zero());
      for (std::size_t j = 0; j < m_; ++j)
        particles[j].map.for_each(
            [&](std::size_t i, const LandmarkEstimate& l) { out.landmarks[i] += w[j] * l.mean; });
      out.ids.assign(id_of_slot_.begin(), id_of_slot_.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      const std::size_t best =
          static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
      particles[best].map.for_each([&](std::size_t, const LandmarkEstimate& l) {
        out.landmarks.push_back(l.mean);
        out.ids.push_back(-1);
      });
    }
    return out;
  }

  const SlamStats& stats() const override { return stats_; }

  std::size_t map_bytes() const override {
    std::unordered_set<const void*> seen;
    std::size_t total = 0;
    for (const auto& p : engine_.particles()) total += p.map.unique_bytes(seen);
    return total;
  }

 private:
  void compute_estimate() {
    // Headings stay on the branch of the particles (the truth is unwrapped too).
    const auto& moments = pose_moments_(engine_.particles(), engine_.weights(),
                                        [](const Particle& p) -> const Pose& { return p.x; });
    estimate_.mean = moments.mean;
    estimate_.cov = moments.covariance;
  }

  // One particle's move, proposal and map update; returns its log weight increment (-inf:
  // weight zero). Writes only to particle j and outcome j.
  double step_particle(std::size_t j, Particle& p, std::uint64_t n, const Control& u,
                       std::span<const Observation> obs, std::size_t slots_before) {
    thread_local std::vector<KnownLandmark> known;
    thread_local std::vector<Measurement> fresh;
    ParticleOutcome& oc = outcome_[j];
    oc.reset();
    const Pose f = model_.predict(p.x, u);
    const Mat<3> sigma1 = model_.process_covariance(p.x, u);
    const Eigen::LLT<Mat<3>> llt1(sigma1);
    if (llt1.info() != Eigen::Success || !f.allFinite()) {
      p.x = f.allFinite() ? f : p.x;
      if (opt_.association == Association::kKnown)  // needs neither f nor Sigma1
        associate(p, f, sigma1, obs, slots_before, known, fresh);
      return zero_weight(p, fresh, oc);
    }
    associate(p, f, sigma1, obs, slots_before, known, fresh);
    if (known.size() > proposal_.max_known_landmarks()) {  // refused after the loop (step())
      oc.known_over_limit = known.size();
      p.x = f;
      return zero_weight(p, fresh, oc);
    }
    const AnyPoseProposal::Step step{opt_.sensor, f, sigma1, llt1, known};
    Rng rng({opt_.seed, n, j, proposal_.purpose()});
    if (known.empty() && fresh.size() == 1)
      if (const auto joint = proposal_.propose_with_new_landmark(step, fresh[0], rng))
        return place_with_new_landmark(p, f, fresh[0], *joint, oc);
    PoseDraw d;
    if (known.empty()) {
      d.x = draw_from_motion(step, rng);
    } else {
      d = proposal_.propose(step, rng);
      if (d.newton_solved) {
        oc.newton_iterations += d.newton_iterations;
        ++oc.newton_solves;
        if (!d.newton_converged) ++oc.newton_not_converged;
      }
    }
    if (d.failed || !d.x.allFinite() || std::isnan(d.log_weight)) {
      p.x = f;
      return zero_weight(p, fresh, oc);
    }
    p.x = d.x;
    update_known(p, known, oc);
    return add_new_landmarks(p, fresh, oc, d.log_weight);
  }

  // A particle that could not be moved gets weight zero. Under known association all particles
  // hold the same landmark slots, so it still places this step's new landmarks (at its pose): if
  // every weight vanishes the engine makes them uniform, and this particle may then be drawn.
  double zero_weight(Particle& p, std::span<const Measurement> fresh, ParticleOutcome& oc) const {
    if (opt_.association == Association::kKnown) add_new_landmarks(p, fresh, oc, 0.0);
    return -std::numeric_limits<double>::infinity();
  }

  // The detections of this step split into known landmarks of particle p (as its map was before
  // the step) and new ones.
  void associate(const Particle& p, const Pose& f, const Mat<3>& sigma1,
                 std::span<const Observation> obs, std::size_t slots_before,
                 std::vector<KnownLandmark>& known, std::vector<Measurement>& fresh) const {
    thread_local std::vector<std::uint32_t> candidates;
    known.clear();
    fresh.clear();
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (use_[i] == 0) continue;
      if (opt_.association == Association::kKnown) {
        const auto slot = static_cast<std::size_t>(slots_[i]);
        if (slot >= slots_before)
          fresh.push_back(obs[i].z);
        else
          known.push_back(known_landmark(slot, obs[i].z, p.map.get(slot)));
        continue;
      }
      // Same association either way (landmark_index.hpp); the index makes it O(1) in N.
      const RangeBearingSensor& s = opt_.sensor;
      const auto a =
          !opt_.association_index || p.map.size() < kIndexedAssociationMinLandmarks
              ? associate_scan(p.map, s, f, sigma1, obs[i].z, opt_.gate_chi2, cov_trace_bound_)
              : associate_indexed(p.map, index_, s, f, sigma1, obs[i].z, opt_.gate_chi2,
                                  candidates);
      if (a.matched()) {
        const auto slot = static_cast<std::size_t>(a.index);
        known.push_back(known_landmark(slot, obs[i].z, p.map.get(slot)));
      } else {
        fresh.push_back(obs[i].z);
      }
    }
  }

  // The only detection is of a new landmark and the proposal drew the pose and the landmark
  // jointly (implicit SLAM (A)); the weight gains p0 / z_range (NewLandmarkDraw).
  double place_with_new_landmark(Particle& p, const Pose& f, const Measurement& z,
                                 const NewLandmarkDraw& d, ParticleOutcome& oc) const {
    p.x = f;
    if (d.failed) return zero_weight(p, std::span<const Measurement>(&z, 1), oc);
    const double log_w = d.log_weight + std::log(opt_.new_landmark_density) - std::log(z(0));
    if (!d.x.allFinite() || !d.m.allFinite() || std::isnan(log_w))
      return zero_weight(p, std::span<const Measurement>(&z, 1), oc);
    p.x = d.x;
    const LandmarkEstimate l = new_landmark(p.x, d.m, z);
    oc.moved.emplace_back(static_cast<std::uint32_t>(p.map.size()), l);
    p.map.push_back(l);
    ++oc.new_landmarks;
    return log_w;
  }

  // A new landmark at m, seen as z from x: a point (covariance zero) or an EKF landmark with the
  // covariance G_z Sigma2 G_z^T of the inverse measurement.
  LandmarkEstimate new_landmark(const Pose& x, const Landmark& m, const Measurement& z) const {
    if (point_landmarks_) return {m, Mat<2>::Zero()};
    const Mat<2>& r = opt_.sensor.noise_covariance();
    const Mat<2> gz = RangeBearingSensor::inverse_jacobian_measurement(x, z);
    return {m, Mat<2>(gz * r * gz.transpose())};
  }

  // EKF updates of the known landmarks at the sampled pose; (A)'s point landmarks stay fixed.
  void update_known(Particle& p, std::span<const KnownLandmark> known, ParticleOutcome& oc) const {
    if (point_landmarks_) {
      oc.updates += static_cast<int>(known.size());
      return;
    }
    const RangeBearingSensor& s = opt_.sensor;
    const Mat<2>& r = s.noise_covariance();
    for (const auto& k : known) {
      LandmarkEstimate l{k.mean, k.cov};
      const Mat<2> hm = s.jacobian_landmark(p.x, l.mean);
      const Eigen::LLT<Mat<2>> llt(hm * l.cov * hm.transpose() + r);
      if (llt.info() != Eigen::Success) continue;
      const Measurement nu = -RangeBearingSensor::residual(s.predict(p.x, l.mean), k.z);
      const Eigen::Matrix<double, 2, 2> pht = l.cov * hm.transpose();
      const Mat<2> gain = llt.solve(pht.transpose()).transpose();
      l.mean += gain * nu;
      const Mat<2> a = Mat<2>::Identity() - gain * hm;
      Mat<2> c = a * l.cov * a.transpose() + gain * r * gain.transpose();
      l.cov = 0.5 * (c + c.transpose());
      p.map.set(k.slot, l);
      // Registered again when it changed cell or covariance class (and for the trace bound).
      if (opt_.association == Association::kMaximumLikelihood)
        oc.moved.emplace_back(static_cast<std::uint32_t>(k.slot), l);
      ++oc.updates;
    }
  }

  // New landmarks placed by inverting the detections at the sampled pose; each contributes the
  // density p0 to the weight (spec §3.10). Returns log_w with those factors.
  double add_new_landmarks(Particle& p, std::span<const Measurement> fresh, ParticleOutcome& oc,
                           double log_w) const {
    for (const Measurement& z : fresh) {
      const LandmarkEstimate fresh_landmark =
          new_landmark(p.x, RangeBearingSensor::inverse(p.x, z), z);
      oc.moved.emplace_back(static_cast<std::uint32_t>(p.map.size()), fresh_landmark);
      p.map.push_back(fresh_landmark);
      log_w += std::log(opt_.new_landmark_density);
      ++oc.new_landmarks;
    }
    return log_w;
  }

  SlamOptions opt_;
  robot::AnyMotionModel base_;   ///< the model at its nominal step
  robot::AnyMotionModel model_;  ///< the model for the current step length
  std::size_t m_;
  filter::ParticleEngine<Particle> engine_;
  filter::PoseMoments pose_moments_{true};
  AnyPoseProposal proposal_;
  bool point_landmarks_;  ///< the proposal's landmark model: points fixed at creation, or EKF
  std::vector<ParticleOutcome> outcome_;
  // Known association: the slot of each landmark id. A hash map, not a table indexed by id: ids
  // are any int in [0, 2^31 - 1], and a table up to the largest would take 8 GiB.
  std::unordered_map<int, int> slot_of_id_;
  std::vector<int> id_of_slot_;
  std::vector<int> slots_, use_;
  PoseEstimate estimate_;
  SlamStats stats_;
  // ML association: one grid index shared by all particles, and an upper bound on the traces of
  // all landmark covariances ever written (for the range check of the scan).
  LandmarkGridIndex index_;
  double cov_trace_bound_ = 0.0;
};

}  // namespace

std::unique_ptr<SlamFilter> make_slam_filter(const SlamOptions& options, const Pose& x0) {
  options.validate();
  require(x0.allFinite(), "SLAM filter: expected a finite initial pose, got ({}, {}, {})", x0(0),
          x0(1), x0(2));
  if (options.method == SlamMethod::kEkf) return std::make_unique<EkfSlamFilter>(options, x0);
  return make_particle_slam_filter(options, x0, pose_proposal(options));
}

AnyPoseProposal pose_proposal(const SlamOptions& o) {
  switch (o.method) {
    case SlamMethod::kFastSlam1:
      return FastSlam1Proposal{};
    case SlamMethod::kFastSlam2:
      return FastSlam2Proposal{};
    case SlamMethod::kImplicit:
    case SlamMethod::kImplicitRb:
      return ImplicitPoseProposal{
          o.method == SlamMethod::kImplicit,
          pose_newton_options(o.newton_max_iterations, o.newton_decrement_tolerance)};
    case SlamMethod::kEkf:
      break;
  }
  throw InvalidArgument("SLAM: EKF-SLAM is not a particle method and has no pose proposal");
}

std::unique_ptr<SlamFilter> make_particle_slam_filter(const SlamOptions& options, const Pose& x0,
                                                      AnyPoseProposal proposal) {
  options.validate();
  require(x0.allFinite(), "SLAM filter: expected a finite initial pose, got ({}, {}, {})", x0(0),
          x0(1), x0(2));
  return std::make_unique<ParticleSlamFilter>(options, x0, std::move(proposal));
}

}  // namespace implicit::slam
