#pragma once
// The robot layer's shared vocabulary: poses, controls, landmarks and measurements, and the
// small matrices between them. Models, sensors, maps and readers include this header, never
// another model, for a type name.
//
// Conventions used throughout robot/: a pose is (x [m], y [m], heading [rad]) in the world frame,
// heading counter-clockwise from the x axis and never wrapped inside a model (residuals are
// wrapped); a Jacobian J_out_in is d out / d in.

#include <cmath>

#include "implicit/core/types.hpp"

namespace implicit::robot {

using Pose = Vec<3>;         ///< (x [m], y [m], heading [rad]); heading may be left unwrapped
using Control = Vec<2>;      ///< the Ute's and the unicycle's control (speed, steering or turn rate)
using Landmark = Vec<2>;     ///< a point landmark (east [m], north [m])
using Measurement = Vec<2>;  ///< a range-bearing detection (range [m], bearing [rad])
using Mat2 = Mat<2>;
using Mat3 = Mat<3>;
using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat32 = Eigen::Matrix<double, 3, 2>;

/// a ⊕ d: the pose reached by moving d = (dx, dy, dtheta), given in a's own frame, from a.
inline Pose compose(const Pose& a, const Pose& d) {
  const double c = std::cos(a(2)), s = std::sin(a(2));
  return Pose(a(0) + c * d(0) - s * d(1), a(1) + s * d(0) + c * d(1), a(2) + d(2));
}

/// The motion from a to b in a's frame: the d with compose(a, d) = b (heading
/// difference not wrapped).
inline Pose between(const Pose& a, const Pose& b) {
  const double c = std::cos(a(2)), s = std::sin(a(2));
  const double dx = b(0) - a(0), dy = b(1) - a(1);
  return Pose(c * dx + s * dy, -s * dx + c * dy, b(2) - a(2));
}

}  // namespace implicit::robot
