#include "implicit/filter/pose_objective.hpp"

namespace implicit::filter {

// A Newton decrement g^T H^-1 g below 1e-2 puts F within about 5e-3 of the minimum of its
// quadratic model, and a centre that far off adds a variance of about g^T H^-1 g = 1e-2 to the
// log-weights (the sample's offset from the minimum is L^-T xi, so the linear term g^T L^-T xi):
// far below the spread of |xi|^2 / 2 (variance 3/2 in three dimensions) and the log-weights'
// own spread on real scans (ESS/M about 0.4). On ACES it took 22.6 evaluations per particle and
// update instead of 27.8 at 1e-3, at the same RMSE and ESS (docs/performance.md, "Newton's
// stopping rule"). The distances are stored as float (7 digits), so F itself is only known to
// about 1e-5 relative. A step below 1e-5 (m, rad) ends it too, and 20 iterations at most; the
// Armijo line search makes every step a descent.
NewtonOptions scan_newton_options() {
  NewtonOptions o;
  o.max_iterations = 20;
  o.gradient_tolerance = 0.0;
  o.step_tolerance = 1e-5;
  o.relative_step_tolerance = false;
  o.decrement_tolerance = 1e-2;
  o.armijo = 1e-4;
  o.max_backtracks = 30;
  o.fallback = HessianFallback::kGaussNewton;
  o.damping = false;
  return o;
}

}  // namespace implicit::filter
