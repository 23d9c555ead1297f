#pragma once
// Shared by the laser bindings (laser.cpp: grids, maps, logs, the likelihood field and the
// odometry model; laser_beam.cpp: the beam model; laser_filter.cpp: the steppable filter and the
// one-call run). Python hands
// over loosely typed objects: every argument is converted here, and a bad one raises
// InvalidArgument naming it, before any C++ object sees it.

#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "common.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/robot/beam_model.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/likelihood_field.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/odometry_model.hpp"

namespace implicit::python::laser {

// The files of the laser bindings may be compiled as one unit (IMPLICIT_UNITY_BUILD): what they
// share is declared here once, and each keeps its own helpers in an unnamed namespace under
// implicit::python::laser, apart from the other bindings' helpers in implicit::python.
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr long long kMaxInt = std::numeric_limits<long long>::max();

// type_name, number_arg, int_arg, seed_arg, bool_arg, choice_arg and path_arg: common.hpp.

/// A CARMEN log (or a bag read as one) as the dict of implicit.laser.read_carmen.
py::dict carmen_log_dict(const robot::CarmenLog& log);

/// An (n,) array of finite values.
Vec<3> vec3_arg(const py::handle& o, const std::string& name);
/// (x forward [m], y left [m], yaw [rad]) of the laser on the robot.
robot::LaserMount mount_arg(const py::handle& o, const std::string& name);
/// The grid bound as implicit.laser.OccupancyGrid.
const robot::OccupancyGrid& grid_arg(const py::handle& o, const std::string& name);
/// Odometry alphas from a (4,) array of finite values >= 0.
robot::OdometryAlphas alphas_arg(const py::handle& o, const std::string& name);

/// One scan from its fields; `prefix` goes in front of each field's name in messages (e.g.
/// "scans[3]."), so that every bad field is named.
robot::LaserScan scan_arg(const py::handle& ranges, const py::handle& angle_min,
                          const py::handle& angle_increment, const py::handle& range_min,
                          const py::handle& range_max, const std::string& prefix = "");

/// Scans from the dict read_carmen returns (per-scan arrays) or from a list of scan dicts
/// (ranges, angle_min, angle_increment, range_max, optional range_min).
std::vector<robot::LaserScan> scans_arg(const py::handle& o, const std::string& name);

/// The likelihood field's settings as Python passes them (keywords of LikelihoodField).
struct LaserSpec {
  robot::LikelihoodFieldParams params;
  robot::LaserMount mount;
};
/// Reads the LikelihoodField keywords from `kw` (missing ones keep their defaults); a key that
/// is not one of them is refused, naming `where` (e.g. "laser").
LaserSpec laser_spec(const py::dict& kw, const std::string& where);
/// The keywords of LikelihoodField, for messages.
extern const char* const kLaserKeywords;

/// The beam model's settings as Python passes them (keywords of BeamModel).
struct BeamSpec {
  robot::BeamModelParams params;
  robot::LaserMount mount;
};
/// Reads the BeamModel keywords from `kw` (missing ones keep their defaults); a key that is not
/// one of them is refused, naming `where`.
BeamSpec beam_spec(const py::dict& kw, const std::string& where);
/// The keywords of BeamModel, for messages.
extern const char* const kBeamKeywords;

/// log p(scan | x) (N,) of a laser model for each robot pose x of `poses` (N, 3): the scan is
/// prepared once, the poses are scored in parallel without the interpreter's lock.
template <typename Model>
py::array_t<double> log_likelihoods(const Model& model, const py::handle& poses,
                                    const robot::LaserScan& scan) {
  const Array x = require_shape(poses, "poses", {-1, 3});
  const typename Model::Prepared z = model.prepare(scan);
  std::vector<double> out(static_cast<std::size_t>(x.shape(0)));
  const double* p = x.data();
  {
    py::gil_scoped_release unlocked;
    parallel_for(out.size(), [&](std::size_t k) {
      out[k] = model.log_likelihood(z, robot::Pose(p[3 * k], p[3 * k + 1], p[3 * k + 2]));
    });
  }
  return adopt_vector(std::move(out));
}

/// The Interpolation named by text (the name of the argument in messages: "interpolation").
robot::Interpolation interpolation_arg(const py::handle& o, const std::string& name);
robot::BeamAggregation aggregation_arg(const py::handle& o, const std::string& name);

/// implicit.laser.BeamModel (laser_beam.cpp).
void bind_beam(py::module_& m);
/// implicit.laser.ParticleFilter and implicit.laser.run (laser_filter.cpp).
void init_laser_filter(py::module_& m);

}  // namespace implicit::python::laser
