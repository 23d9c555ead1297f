#pragma once
// Conversions shared by the robot bindings (robot.cpp, data.cpp, filter.cpp).
#include "common.hpp"
#include "implicit/robot/landmark_map.hpp"

namespace implicit::python {
/// A landmark map with ids 0..K-1 from a (K, 2) array of positions [m].
robot::LandmarkMap landmark_map(const py::object& landmarks);
/// The (K, 2) positions of a map.
py::array_t<double> landmark_points(const robot::LandmarkMap& map);
}  // namespace implicit::python
