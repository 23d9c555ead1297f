#pragma once
// The options and outcomes of minimising F, shared by the Newton kernel (newton.hpp) and its
// wrappers minimize() (minimize.hpp) and minimize_banded() (banded.hpp).
//
// A header of its own so that newton.hpp can use them while minimize.hpp and banded.hpp, which
// run on newton.hpp, include it in turn.

#include <string_view>

namespace implicit {

enum class MinimizeStatus {
  kConverged,            ///< gradient or step below tolerance, Hessian SPD at the end
  kMaxIterations,        ///< iteration limit reached
  kNonFinite,            ///< F, gradient or Hessian not finite at the start point or a step
  kNotPositiveDefinite,  ///< converged, but the Hessian at the end is not positive definite
  kLineSearchFailed,     ///< no step decreased F (F non-smooth, or wrong derivatives)
};

inline std::string_view to_string(MinimizeStatus s) {
  switch (s) {
    case MinimizeStatus::kConverged:
      return "converged";
    case MinimizeStatus::kMaxIterations:
      return "max_iterations";
    case MinimizeStatus::kNonFinite:
      return "non_finite";
    case MinimizeStatus::kNotPositiveDefinite:
      return "not_positive_definite";
    case MinimizeStatus::kLineSearchFailed:
      return "line_search_failed";
  }
  return "unknown";
}

struct MinimizeOptions {
  int max_iterations = 100;
  double gradient_tolerance = 1e-10;  ///< stop when max|grad F| <= this
  double step_tolerance = 1e-12;      ///< stop when max|step| <= this * (1 + max|x|)
  double armijo = 1e-4;               ///< sufficient-decrease constant
  int max_backtracks = 60;
};

}  // namespace implicit
