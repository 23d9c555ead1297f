// implicit.laser.BeamModel: the beam model (robot/beam_model.hpp) on a grid, with nav2 AMCL's
// keyword names, scoring many poses for one scan in one call. ParticleFilter takes it with the
// bootstrap proposal (laser_filter.cpp).

#include <memory>

#include <fmt/format.h>

#include "laser.hpp"

namespace implicit::python::laser {

const char* const kBeamKeywords =
    "z_hit, z_short, z_max, z_rand, sigma_hit, lambda_short, max_beams, laser_max_range, "
    "laser_min_range, mount";

namespace {

/// A range limit: None keeps the scan's own (the model's "<= 0"), else a finite number > 0.
double range_limit_arg(const py::handle& o, const std::string& name) {
  return o.is_none() ? -1.0 : number_arg(o, name, 0.0, kInf, true);
}

}  // namespace

BeamSpec beam_spec(const py::dict& kw, const std::string& where) {
  BeamSpec spec;
  robot::BeamModelParams& p = spec.params;
  for (const auto& item : kw) {
    const std::string key = py::str(item.first);
    const py::handle v = item.second;
    // The weights: z_hit carries the map, so it must be positive; the others may be switched off.
    if (key == "z_hit")
      p.z_hit = number_arg(v, key, 0.0, kInf, true);
    else if (key == "z_short")
      p.z_short = number_arg(v, key, 0.0, kInf);
    else if (key == "z_max")
      p.z_max = number_arg(v, key, 0.0, kInf);
    else if (key == "z_rand")
      p.z_rand = number_arg(v, key, 0.0, kInf);
    else if (key == "sigma_hit")
      p.sigma_hit = number_arg(v, key, 0.0, kInf, true);
    else if (key == "lambda_short")
      p.lambda_short = number_arg(v, key, 0.0, kInf, true);
    else if (key == "max_beams")
      p.max_beams = static_cast<int>(int_arg(v, key, 1, 1'000'000));
    else if (key == "laser_max_range")
      p.laser_max_range = range_limit_arg(v, key);
    else if (key == "laser_min_range")
      p.laser_min_range = range_limit_arg(v, key);
    else if (key == "mount")
      spec.mount = mount_arg(v, key);
    else
      throw InvalidArgument(fmt::format("{}: unknown keyword '{}' (expected one of {})", where,
                                        printable(key), kBeamKeywords));
  }
  return spec;
}

namespace {

using namespace py::literals;

constexpr const char* kBeamDoc = R"doc(
The beam model of a laser (Probabilistic Robotics §6.3, nav2 AMCL's parameter names; spec §3.12,
"The beam model") on a grid. Beam i's expected range zhat_i(x) is the ray cast from the laser at
robot pose x to the first occupied cell, capped at R, the maximum range (laser_max_range, else
the scan's range_max). With S = z_hit + z_short + z_max + z_rand a reading r < R has density

    p(r | zhat) = [ z_hit N(r; zhat, sigma_hit^2)
                  + z_short l e^(-l r) / (1 - e^(-l zhat)) [r <= zhat]     (l = lambda_short)
                  + z_rand / R ] / S

and a reading without return (r >= R) has probability [z_hit Q((R - zhat) / sigma_hit) + z_max]
/ S, Q the standard normal's upper tail. log p(scan | x) sums over at most max_beams beams evenly
spaced over the scan; readings below the minimum range (laser_min_range, else the scan's
range_min) are skipped; unlike the likelihood field's, readings without return count.

BeamModel(grid, z_hit=0.5, z_short=0.05, z_max=0.05, z_rand=0.5, sigma_hit=0.2,
          lambda_short=0.1, max_beams=60, laser_max_range=None, laser_min_range=None,
          mount=(0, 0, 0))

mount is the laser's pose (x forward, y left [m], yaw [rad]) on the robot. The expected range is
a step function of the pose, so the model has no derivatives (differentiable is False):
ParticleFilter(grid, proposal="bootstrap", laser=model) runs a filter on it, and the implicit
proposal refuses it.

log_likelihood(poses (N, 3), ranges, angle_min, angle_increment, range_min, range_max) -> (N,),
one call for all poses.

Example::

    beam = implicit.laser.BeamModel(grid, sigma_hit=0.1)
    scan = implicit.laser.simulate_scan(grid, [1.0, 1.0, 0.0])
    beam.log_likelihood(np.array([[1.0, 1.0, 0.0], [1.1, 1.0, 0.0]]), **scan))doc";

robot::BeamModel make_beam(const py::object& grid, const py::dict& kw) {
  const robot::OccupancyGrid& g = grid_arg(grid, "grid");
  const BeamSpec spec = beam_spec(kw, "BeamModel");
  return robot::BeamModel(std::make_shared<const robot::OccupancyGrid>(g), spec.params, spec.mount);
}

}  // namespace

void bind_beam(py::module_& m) {
  py::class_<robot::BeamModel>(m, "BeamModel", kBeamDoc)
      .def(py::init([](const py::object& grid, const py::object& z_hit, const py::object& z_short,
                       const py::object& z_max, const py::object& z_rand,
                       const py::object& sigma_hit, const py::object& lambda_short,
                       const py::object& max_beams, const py::object& laser_max_range,
                       const py::object& laser_min_range, const py::object& mount) {
             py::dict kw("z_hit"_a = z_hit, "z_short"_a = z_short, "z_max"_a = z_max,
                         "z_rand"_a = z_rand, "sigma_hit"_a = sigma_hit,
                         "lambda_short"_a = lambda_short, "max_beams"_a = max_beams,
                         "laser_max_range"_a = laser_max_range,
                         "laser_min_range"_a = laser_min_range, "mount"_a = mount);
             return make_beam(grid, kw);
           }),
           py::arg("grid"), py::arg("z_hit") = 0.5, py::arg("z_short") = 0.05,
           py::arg("z_max") = 0.05, py::arg("z_rand") = 0.5, py::arg("sigma_hit") = 0.2,
           py::arg("lambda_short") = 0.1, py::arg("max_beams") = 60,
           py::arg("laser_max_range") = py::none(), py::arg("laser_min_range") = py::none(),
           py::arg("mount") = py::make_tuple(0.0, 0.0, 0.0))
      .def_property_readonly("differentiable", &robot::BeamModel::differentiable,
                             "False: the expected range is a step function of the pose.")
      .def(
          "log_likelihood",
          [](const robot::BeamModel& b, const py::object& poses, const py::object& ranges,
             const py::object& angle_min, const py::object& angle_increment,
             const py::object& range_min, const py::object& range_max) {
            return log_likelihoods(
                b, poses, scan_arg(ranges, angle_min, angle_increment, range_min, range_max));
          },
          py::arg("poses"), py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"),
          py::arg("range_min"), py::arg("range_max"),
          "log p(scan | x) (N,) for each robot pose x of poses (N, 3): one ray cast per used "
          "beam; the scan's ranges [m] (+inf: no return) at bearings angle_min + i "
          "angle_increment [rad].")
      .def("__repr__", [](const robot::BeamModel& b) {
        const robot::BeamModelParams& p = b.params();
        return fmt::format(
            "BeamModel(z_hit={}, z_short={}, z_max={}, z_rand={}, sigma_hit={}, lambda_short={}, "
            "max_beams={})",
            p.z_hit, p.z_short, p.z_max, p.z_rand, p.sigma_hit, p.lambda_short, p.max_beams);
      });
}

}  // namespace implicit::python::laser
