#pragma once
// Recovery of a lost localization filter (spec §3.11): a "lost" signal from the likelihood of the
// data, and the fraction of particles to draw from a recovery source instead of the motion model.
//
// The signal is augmented MCL's (Thrun, Burgard & Fox, Probabilistic Robotics, Table 8.3): two
// exponential averages of the likelihood increment, w_slow and w_fast, and the injection
// probability p = max(0, 1 - w_fast / w_slow). When the data suddenly fit worse than they used to
// (w_fast drops below w_slow), p grows.
//
// Two departures from ROS AMCL, both deliberate:
//  * The averaged quantity is the likelihood increment PER DETECTION, exp(increment / count).
//    Beacon scans see 1 to 6 landmarks, and the product of 6 densities has another scale than one;
//    averaging the raw increment would read every change in the count as a change in fit. (AMCL's
//    laser scans have a fixed number of beams.)
//  * The injected particles keep exact importance weights. The motion model is read as a
//    mixture: with probability epsilon (kidnap_probability) per update step the robot is moved to
//    a pose drawn from u (uniform over the map), else it follows the motion model. A particle that
//    is injected (probability p) from the source g gets the increment
//        log(epsilon / p) + log u(x) + log p(z | x) - log g(x),
//    the others their proposal's increment plus log((1 - epsilon) / (1 - p)). This is importance
//    sampling on the space extended by the "moved or not" indicator, so the filter stays a
//    consistent estimator of that model whatever p is: the source decides only how efficiently
//    the kidnapped hypothesis is explored. AMCL gives injected particles equal weights instead.

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/rng.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

/// Parameters of recovery, named as in ROS AMCL where they mean the same.
struct RecoveryOptions {
  bool enabled = false;
  double recovery_alpha_slow = 0.001;  ///< rate of the slow average (AMCL: 0.001 suggested)
  double recovery_alpha_fast = 0.1;    ///< rate of the fast average (AMCL: 0.1 suggested)
  /// epsilon: prior probability per update step that the robot was moved without odometry.
  double kidnap_probability = 1e-3;
  /// Upper limit of the injected fraction (keeps some particles on the motion model).
  double max_injection = 0.5;
};

inline void validate(const RecoveryOptions& o) {
  require(o.recovery_alpha_slow > 0 && o.recovery_alpha_slow < 1,
          "recovery: expected recovery_alpha_slow in (0, 1), got {}", o.recovery_alpha_slow);
  require(o.recovery_alpha_fast > o.recovery_alpha_slow && o.recovery_alpha_fast <= 1,
          "recovery: expected recovery_alpha_fast in (recovery_alpha_slow, 1], got {}",
          o.recovery_alpha_fast);
  require(o.kidnap_probability > 0 && o.kidnap_probability < 1,
          "recovery: expected kidnap_probability in (0, 1), got {}", o.kidnap_probability);
  require(o.max_injection > 0 && o.max_injection < 1,
          "recovery: expected max_injection in (0, 1), got {}", o.max_injection);
}

/// w_slow and w_fast, kept as logarithms (a per-detection density can be far from 1).
class LikelihoodAverages {
 public:
  /// Adds one update step: `log_increment` is the engine's log marginal-likelihood increment,
  /// `detections` the number of detections it came from (steps with none are not averaged).
  void update(double log_increment, int detections, const RecoveryOptions& o) {
    if (detections <= 0) return;
    // A step where every weight was zero counts as the lowest fit seen so far, not as -inf (which
    // would pin w_fast at zero forever).
    const double w = std::isfinite(log_increment)
                         ? log_increment / detections
                         : std::min(log_fast_, log_slow_) - 10.0;  // e^-10: "far worse"
    if (!started_) {
      log_slow_ = log_fast_ = w;
      started_ = true;
      return;
    }
    log_slow_ = mix(log_slow_, w, o.recovery_alpha_slow);
    log_fast_ = mix(log_fast_, w, o.recovery_alpha_fast);
  }

  /// p = max(0, 1 - w_fast / w_slow), at most `max_injection`.
  double injection_probability(const RecoveryOptions& o) const {
    if (!started_) return 0.0;
    // Below 1e-9 (round-off of two equal averages) nothing would be injected at any M: 0, so
    // that a filter that never looks lost is bit-identical to one without recovery.
    const double p = -std::expm1(log_fast_ - log_slow_);
    return p < 1e-9 ? 0.0 : std::min(p, o.max_injection);
  }

  double log_slow() const { return log_slow_; }
  double log_fast() const { return log_fast_; }
  void reset() { started_ = false; }

 private:
  /// log((1 - alpha) e^a + alpha e^b) without overflow: w += alpha (w_new - w) in log space.
  static double mix(double a, double b, double alpha) {
    const double x = std::log1p(-alpha) + a, y = std::log(alpha) + b;
    const double top = std::max(x, y);
    return top + std::log(std::exp(x - top) + std::exp(y - top));
  }

  bool started_ = false;
  double log_slow_ = 0.0, log_fast_ = 0.0;
};

/// Where recovery draws its particles: prepared once per update step, then drawn per particle
/// (from several threads at once: draw must not change the source). `Context` is the filter's
/// ObservationContext (the step's motion model, control, observation model and prepared
/// observation).
template <typename Context>
class RecoverySource {
 public:
  virtual ~RecoverySource() = default;
  /// Called once per update step before any draw, e.g. to find the poses that explain these
  /// detections. Returns false when it has nothing to propose (nothing is injected this step).
  virtual bool prepare(const Context& ctx) = 0;
  /// Draws a pose x from the source g using only `rng`; returns log u(x) + log p(z | x) - log g(x)
  /// (u: the density the robot is moved to when kidnapped; -inf: weight zero).
  virtual double draw(const Context& ctx, Rng& rng, robot::Pose& x) const = 0;
};

}  // namespace implicit::filter
