#include "implicit/robot/simulate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

namespace implicit::robot {

Driver square_route_driver(double speed, double side, bool unicycle) {
  require(speed > 0 && side > 0,
          "simulate: expected a positive speed and route side, got {} and {}", speed, side);
  // The corner being approached is state of the driver: shared so that copies agree.
  auto corner = std::make_shared<int>(1);
  return [=](const Pose& x, double /*dt*/) {
    const std::array<Vec<2>, 4> corners{Vec<2>(0, 0), Vec<2>(side, 0), Vec<2>(side, side),
                                        Vec<2>(0, side)};
    if ((corners[static_cast<std::size_t>(*corner)] - x.head<2>()).norm() < 0.1 * side)
      *corner = (*corner + 1) % 4;
    const Vec<2> d = corners[static_cast<std::size_t>(*corner)] - x.head<2>();
    const double error = wrap_angle(std::atan2(d(1), d(0)) - x(2));
    if (unicycle) {
      // Far off course: stop and turn on the spot; otherwise steer proportionally.
      const double v = std::abs(error) > kPi / 3 ? 0.0 : speed;
      return Control(v, std::clamp(1.5 * error, -1.0, 1.0));
    }
    return Control(speed, std::clamp(error, -0.5, 0.5));
  };
}

}  // namespace implicit::robot
