#include "implicit/filter/pose_objective.hpp"

namespace implicit::filter {

// A Newton decrement g^T H^-1 g below 1e-3 puts F within about 5e-4 of the minimum of its
// quadratic model: far below the spread of |xi|^2 / 2 (variance 3/2 in three dimensions), so
// further iterations could not change the effective sample size measurably. The distances are
// stored as float (7 digits), so F itself is only known to about 1e-5 relative: tighter rules
// would spend their iterations on rounding. A step below 1e-5 (m, rad) ends it too, and 20
// iterations at most; the Armijo line search makes every step a descent.
NewtonOptions scan_newton_options() {
  NewtonOptions o;
  o.max_iterations = 20;
  o.gradient_tolerance = 0.0;
  o.step_tolerance = 1e-5;
  o.relative_step_tolerance = false;
  o.decrement_tolerance = 1e-3;
  o.armijo = 1e-4;
  o.max_backtracks = 30;
  o.fallback = HessianFallback::kGaussNewton;
  o.damping = false;
  return o;
}

}  // namespace implicit::filter
