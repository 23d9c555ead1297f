// implicit.laser: occupancy grids to and from numpy, map files, CARMEN logs, mapping with known
// poses, simulated scans, the likelihood-field model and the odometry motion model. The beam
// model is in laser_beam.cpp, the filter and the one-call run in laser_filter.cpp.

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/rng.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/map_io.hpp"
#include "implicit/robot/scan_simulation.hpp"
#include "laser.hpp"

namespace implicit::python::laser {
namespace {

using namespace py::literals;
using robot::OccupancyGrid;
using robot::Pose;

py::array_t<double> numpy_vec3(const Vec<3>& v) { return py::array_t<double>(3, v.data()); }

py::array_t<double> numpy_mat3(const Mat<3>& m) {
  py::array_t<double> a({3, 3});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.mutable_at(i, j) = m(i, j);
  return a;
}

py::array_t<double> numpy_poses(const std::vector<Pose>& poses) {
  py::array_t<double> a({static_cast<py::ssize_t>(poses.size()), py::ssize_t{3}});
  for (std::size_t k = 0; k < poses.size(); ++k)
    for (int i = 0; i < 3; ++i) a.mutable_at(k, i) = poses[k](i);
  return a;
}

/// The grid from an integer array (height, width), row 0 the lowest y.
OccupancyGrid grid_from_cells(const py::handle& cells, const py::handle& resolution,
                              const py::handle& origin) {
  py::array a = py::array::ensure(cells);
  require(static_cast<bool>(a), "cells: expected a 2-D array of integers, got {}",
          type_name(cells));
  const char kind = a.dtype().kind();
  require(kind == 'i' || kind == 'u',
          "cells: expected integer occupancy values (int8, -1..100), got dtype {}",
          std::string(py::str(a.dtype())));
  require(a.ndim() == 2, "cells: expected a 2-D array (height, width), got shape {}",
          shape_text(a));
  const py::ssize_t height = a.shape(0), width = a.shape(1);
  require(height > 0 && width > 0, "cells: expected at least one row and column, got shape {}",
          shape_text(a));
  require(height * width <= (py::ssize_t{1} << 31), "cells: expected at most 2^31 cells, got {}",
          shape_text(a));
  const double res = number_arg(resolution, "resolution", 0.0, kInf, true);
  const Array o = require_shape(origin, "origin", {2});
  using Cells = py::array_t<long long, py::array::c_style | py::array::forcecast>;
  const Cells c = Cells::ensure(a);
  OccupancyGrid grid(static_cast<int>(width), static_cast<int>(height), res,
                     Vec<2>(o.data()[0], o.data()[1]));
  for (py::ssize_t iy = 0; iy < height; ++iy)
    for (py::ssize_t ix = 0; ix < width; ++ix) {
      const long long v = c.at(iy, ix);
      require(v >= OccupancyGrid::kUnknown && v <= OccupancyGrid::kOccupied,
              "cells: expected values in -1..100, got {} at row {}, column {}", v, iy, ix);
      grid.at(static_cast<int>(ix), static_cast<int>(iy)) = static_cast<std::int8_t>(v);
    }
  return grid;
}

constexpr const char* kGridDoc = R"doc(
An occupancy grid: cells (height, width) of 0 (free) .. 100 (occupied), -1 unknown, each
`resolution` metres square, cell [0, 0]'s lower-left corner at `origin` (x, y) [m]. Row 0 is the
lowest y (a map image shows the highest y first: load_map and save_map flip it).

OccupancyGrid(cells, resolution, origin=(0, 0))

A cell counts as occupied at >= 65 and as free at 0..19 (map_server's thresholds).
Attributes: cells (a copy, int8 (height, width)), resolution [m], origin (x, y), width, height.

Example::

    cells = np.zeros((40, 60), np.int8); cells[:, 30] = 100   # a wall at x = 1.5 m
    grid = implicit.laser.OccupancyGrid(cells, 0.05, origin=(0, 0)))doc";

void bind_grid(py::module_& m) {
  py::class_<OccupancyGrid>(m, "OccupancyGrid", kGridDoc)
      .def(py::init(&grid_from_cells), py::arg("cells"), py::arg("resolution"),
           py::arg("origin") = py::make_tuple(0.0, 0.0))
      .def_property_readonly(
          "cells",
          [](const OccupancyGrid& g) {
            py::array_t<std::int8_t> a({g.height(), g.width()});
            std::copy(g.data().begin(), g.data().end(), a.mutable_data());
            return a;
          },
          "A copy of the cells, int8 (height, width), row 0 the lowest y.")
      .def_property_readonly("resolution", &OccupancyGrid::resolution, "Cell size [m].")
      .def_property_readonly(
          "origin",
          [](const OccupancyGrid& g) { return py::make_tuple(g.origin()(0), g.origin()(1)); },
          "World (x, y) [m] of cell [0, 0]'s lower-left corner.")
      .def_property_readonly("width", &OccupancyGrid::width, "Cells along x.")
      .def_property_readonly("height", &OccupancyGrid::height, "Cells along y.")
      .def("__repr__", [](const OccupancyGrid& g) {
        return fmt::format("OccupancyGrid(width={}, height={}, resolution={}, origin=({}, {}))",
                           g.width(), g.height(), g.resolution(), g.origin()(0), g.origin()(1));
      });
}

py::dict carmen_dict(const robot::CarmenLog& log) {
  const auto n = static_cast<py::ssize_t>(log.scans.size());
  py::array_t<double> times(n), angle_min(n), angle_increment(n), range_min(n), range_max(n);
  py::array_t<long long> lines(n);
  bool same_size = true;
  for (py::ssize_t k = 0; k < n; ++k) {
    const robot::LaserScan& s = log.scans[static_cast<std::size_t>(k)];
    times.mutable_at(k) = s.time;
    angle_min.mutable_at(k) = s.angle_min;
    angle_increment.mutable_at(k) = s.angle_increment;
    range_min.mutable_at(k) = s.range_min;
    range_max.mutable_at(k) = s.range_max;
    lines.mutable_at(k) = static_cast<long long>(log.scan_lines[static_cast<std::size_t>(k)]);
    same_size = same_size && s.size() == log.scans.front().size();
  }
  py::object ranges;
  if (same_size && n > 0) {
    const auto beams = static_cast<py::ssize_t>(log.scans.front().size());
    py::array_t<double> r({n, beams});
    for (py::ssize_t k = 0; k < n; ++k)
      std::copy_n(log.scans[static_cast<std::size_t>(k)].ranges.data(), beams,
                  r.mutable_data(k, 0));
    ranges = r;
  } else {
    py::list r;
    for (const robot::LaserScan& s : log.scans)
      r.append(py::array_t<double>(static_cast<py::ssize_t>(s.size()), s.ranges.data()));
    ranges = r;
  }
  py::dict d;
  d["source"] = log.source;
  d["laser_poses"] = numpy_poses(log.laser_poses);
  d["odometry_poses"] = numpy_poses(log.odometry_poses);
  d["times"] = times;
  d["ranges"] = ranges;
  d["angle_min"] = angle_min;
  d["angle_increment"] = angle_increment;
  d["range_min"] = range_min;
  d["range_max"] = range_max;
  d["lines"] = lines;
  return d;
}

py::dict scan_dict(const robot::LaserScan& s) {
  py::dict d;
  d["ranges"] = py::array_t<double>(static_cast<py::ssize_t>(s.size()), s.ranges.data());
  d["angle_min"] = s.angle_min;
  d["angle_increment"] = s.angle_increment;
  d["range_min"] = s.range_min;
  d["range_max"] = s.range_max;
  return d;
}

void bind_files(py::module_& m) {
  m.def(
      "load_map",
      [](const py::object& yaml_path) { return robot::load_map(path_arg(yaml_path, "yaml_path")); },
      py::arg("yaml_path"),
      "Reads a ROS map_server map (the YAML file and the image it names; docs/formats.md) as an "
      "OccupancyGrid. A malformed file raises implicit.ParseError naming the file and line.");
  m.def(
      "save_map",
      [](const py::object& grid, const py::object& yaml_path) {
        robot::save_map(grid_arg(grid, "grid"), path_arg(yaml_path, "yaml_path"));
      },
      py::arg("grid"), py::arg("yaml_path"),
      "Writes grid as a map_server map: a binary PGM beside yaml_path (same name, .pgm), then "
      "the YAML file. A grid of 0, 100 and -1 only reads back exactly.");
  m.def(
      "read_carmen",
      [](const py::object& path) {
        return carmen_dict(robot::read_carmen(path_arg(path, "path")));
      },
      py::arg("path"),
      "Reads a CARMEN laser log (plain or gzip) into a dict of numpy arrays: laser_poses (N, 3) "
      "and odometry_poses (N, 3) recorded with the scans, times (N,) [s], ranges (N, beams) (a "
      "list of arrays when scans differ in beam count), angle_min, angle_increment, range_min, "
      "range_max (N,) per scan, lines (N,) the scans' lines, source the file name.");
  m.def(
      "bundled_log",
      [](const py::object& name) {
        const std::string n = choice_arg(name, "name", {"intel", "aces", "freiburg-079"});
        const auto path =
            find_share_dir("data", "IMPLICIT_DATA_DIR") / "carmen" / (n + "-corrected.log.gz");
        require(std::filesystem::exists(path), "name: the bundled log '{}' is missing ({})", n,
                path.string());
        return path.string();
      },
      py::arg("name"),
      "The path of a bundled CARMEN log (data/carmen): 'intel', 'aces' or 'freiburg-079'.");
}

void bind_mapping(py::module_& m) {
  m.def(
      "build_map",
      [](const py::object& poses, const py::object& scans, const py::object& mount,
         const py::object& resolution, const py::object& max_range, const py::object& min_echoes) {
        const Array p = require_shape(poses, "poses", {-1, 3});
        const std::vector<robot::LaserScan> s = scans_arg(scans, "scans");
        require(static_cast<std::size_t>(p.shape(0)) == s.size(),
                "poses: expected one pose per scan ({} scans), got {} poses", s.size(), p.shape(0));
        require(!s.empty(), "scans: expected at least one scan, got none");
        std::vector<Pose> robot_poses;
        for (py::ssize_t k = 0; k < p.shape(0); ++k)
          robot_poses.emplace_back(p.at(k, 0), p.at(k, 1), p.at(k, 2));
        robot::GridMappingOptions o;
        o.resolution = number_arg(resolution, "resolution", 0.0, kInf, true);
        o.max_range = number_arg(max_range, "max_range", 0.0, kInf);
        o.min_echoes = static_cast<int>(int_arg(min_echoes, "min_echoes", 0, 255));
        const robot::LaserMount mt = mount_arg(mount, "mount");
        py::gil_scoped_release unlocked;
        return robot::build_map(robot_poses, s, mt, o);
      },
      py::arg("poses"), py::arg("scans"), py::arg("mount") = py::make_tuple(0.0, 0.0, 0.0),
      py::arg("resolution") = 0.05, py::arg("max_range") = 40.0, py::arg("min_echoes") = 2,
      "Occupancy grid mapping with known poses (log-odds, Probabilistic Robotics ch. 9): poses "
      "(N, 3) the robot's, one per scan; scans the dict of read_carmen or a list of scan dicts; "
      "mount the laser's pose on the robot; resolution [m]; beams longer than max_range [m] only "
      "clear cells (0: each scan's range_max); a cell where beams of min_echoes scans ended is "
      "occupied whatever its log-odds (0: off).");
  m.def(
      "simulate_scan",
      [](const py::object& grid, const py::object& pose, const py::object& mount,
         const py::object& beams, const py::object& fov, const py::object& range_min,
         const py::object& range_max, const py::object& range_std, const py::object& seed) {
        const OccupancyGrid& g = grid_arg(grid, "grid");
        const Pose x = vec3_arg(pose, "pose");
        robot::ScanSimulationOptions o;
        o.beams = static_cast<int>(int_arg(beams, "beams", 1, 100000));
        o.field_of_view = number_arg(fov, "field_of_view", 0.0, 2.0 * kPi, true);
        o.range_min = number_arg(range_min, "range_min", 0.0, kInf);
        o.range_max = number_arg(range_max, "range_max", o.range_min, kInf, true);
        o.range_std = number_arg(range_std, "range_std", 0.0, kInf);
        const auto s = seed_arg(seed, "seed");
        Rng rng({s, 0, 0, purpose::kData});
        return scan_dict(robot::simulate_scan(g, x, mount_arg(mount, "mount"), o, rng));
      },
      py::arg("grid"), py::arg("pose"), py::arg("mount") = py::make_tuple(0.0, 0.0, 0.0),
      py::arg("beams") = 181, py::arg("field_of_view") = kPi, py::arg("range_min") = 0.05,
      py::arg("range_max") = 30.0, py::arg("range_std") = 0.02, py::arg("seed") = 0,
      "A laser scan ray-cast on grid from robot pose (3,) with the laser at mount: beams evenly "
      "over field_of_view [rad] centred ahead, Gaussian range noise range_std [m] on hits, "
      "range_max where nothing is hit. Returns a dict (ranges, angle_min, angle_increment, "
      "range_min, range_max): the keywords of LikelihoodField.log_likelihood and "
      "ParticleFilter.step.");
}

/// The model and the distance field it reads (shared: the model keeps a pointer to it).
struct PyLikelihoodField {
  std::shared_ptr<const robot::DistanceField> field;
  robot::LikelihoodFieldModel model;
};

PyLikelihoodField make_field(const py::object& grid, const py::dict& kw) {
  const OccupancyGrid& g = grid_arg(grid, "grid");
  const LaserSpec spec = laser_spec(kw, "LikelihoodField");
  auto field =
      std::make_shared<const robot::DistanceField>(g, spec.params.laser_likelihood_max_dist);
  return PyLikelihoodField{field, robot::LikelihoodFieldModel(field, spec.params, spec.mount)};
}

constexpr const char* kFieldDoc = R"doc(
The likelihood-field laser model (Probabilistic Robotics §6.4, nav2 AMCL's parameters) on a grid:

    log p(scan | x) = sum_i log(z_hit N(d_i; 0, sigma_hit^2) + z_rand / z_max)

d_i the distance from beam i's end point at pose x to the nearest occupied cell (capped at
max_dist [m]), z_max the scan's range_max. Readings >= range_max (no return) and < range_min are
skipped; at most max_beams beams are used, evenly spaced over the scan.

LikelihoodField(grid, z_hit=0.5, z_rand=0.5, sigma_hit=0.2, max_dist=2.0, max_beams=60,
                interpolation="bicubic", aggregation="product", mount=(0, 0, 0))

interpolation of the distance field: "nearest" (AMCL's lookup), "bilinear" or "bicubic" (C1);
aggregation "product" (the likelihood) or "cubed-sum" (nav2's 1 + sum p^3, not a likelihood);
mount the laser's pose (x forward, y left [m], yaw [rad]) on the robot.

log_likelihood(poses (N, 3), ranges, angle_min, angle_increment, range_min, range_max) -> (N,),
one call for all poses. negative_log_likelihood(pose (3,), ...) -> (value, gradient (3,),
gauss_newton (3, 3)), for bilinear or bicubic with the product.

Example::

    field = implicit.laser.LikelihoodField(grid, sigma_hit=0.1)
    scan = implicit.laser.simulate_scan(grid, [1.0, 1.0, 0.0])
    field.log_likelihood(np.array([[1.0, 1.0, 0.0], [1.1, 1.0, 0.0]]), **scan))doc";

void bind_field(py::module_& m) {
  py::class_<PyLikelihoodField>(m, "LikelihoodField", kFieldDoc)
      .def(py::init([](const py::object& grid, const py::object& z_hit, const py::object& z_rand,
                       const py::object& sigma_hit, const py::object& max_dist,
                       const py::object& max_beams, const py::object& interpolation,
                       const py::object& aggregation, const py::object& mount) {
             py::dict kw("z_hit"_a = z_hit, "z_rand"_a = z_rand, "sigma_hit"_a = sigma_hit,
                         "max_dist"_a = max_dist, "max_beams"_a = max_beams,
                         "interpolation"_a = interpolation, "aggregation"_a = aggregation,
                         "mount"_a = mount);
             return make_field(grid, kw);
           }),
           py::arg("grid"), py::arg("z_hit") = 0.5, py::arg("z_rand") = 0.5,
           py::arg("sigma_hit") = 0.2, py::arg("max_dist") = 2.0, py::arg("max_beams") = 60,
           py::arg("interpolation") = "bicubic", py::arg("aggregation") = "product",
           py::arg("mount") = py::make_tuple(0.0, 0.0, 0.0))
      .def_property_readonly("differentiable",
                             [](const PyLikelihoodField& f) { return f.model.differentiable(); })
      .def(
          "log_likelihood",
          [](const PyLikelihoodField& f, const py::object& poses, const py::object& ranges,
             const py::object& angle_min, const py::object& angle_increment,
             const py::object& range_min, const py::object& range_max) {
            return log_likelihoods(
                f.model, poses, scan_arg(ranges, angle_min, angle_increment, range_min, range_max));
          },
          py::arg("poses"), py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"),
          py::arg("range_min"), py::arg("range_max"),
          "log p(scan | x) (N,) for each robot pose x of poses (N, 3); the scan's ranges [m] "
          "(+inf: no return) at bearings angle_min + i angle_increment [rad].")
      .def(
          "negative_log_likelihood",
          [](const PyLikelihoodField& f, const py::object& pose, const py::object& ranges,
             const py::object& angle_min, const py::object& angle_increment,
             const py::object& range_min, const py::object& range_max) {
            require(f.model.differentiable(),
                    "negative_log_likelihood: expected interpolation 'bilinear' or 'bicubic' and "
                    "aggregation 'product', but {}",
                    f.model.why_not_differentiable());
            const Pose x = vec3_arg(pose, "pose");
            const robot::PreparedScan z =
                f.model.prepare(scan_arg(ranges, angle_min, angle_increment, range_min, range_max));
            Vec<3> g = Vec<3>::Zero();
            robot::Mat3 h = robot::Mat3::Zero();
            const double v = f.model.negative_log_likelihood(z, x, &g, &h);
            return py::make_tuple(v, numpy_vec3(g), numpy_mat3(h));
          },
          py::arg("pose"), py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"),
          py::arg("range_min"), py::arg("range_max"),
          "(-log p(scan | pose), its gradient (3,) in the pose, the Gauss-Newton matrix (3, 3) "
          "sum_i w_i (J^T grad d_i)(J^T grad d_i)^T with w_i = hit share / sigma_hit^2).");
}

constexpr const char* kOdometryDoc = R"doc(
The odometry motion model (Probabilistic Robotics §5.4, nav2's alpha1..alpha4). A control u is
the odometry increment (dx [m], dy [m], dtheta [rad]) in the previous odometry frame, read as a
turn rot1, a move trans and a turn rot2 with variances

    alpha1 rot1^2 + alpha2 trans^2,  alpha3 trans^2 + alpha4 (rot1^2 + rot2^2),
    alpha1 rot2^2 + alpha2 trans^2.

OdometryModel(alpha1=0.2, alpha2=0.2, alpha3=0.2, alpha4=0.2)

predict(pose, u) -> pose ⊕ u (3,); covariance(pose, u) -> the linearised Gaussian form's
covariance (3, 3) (with a small floor, always positive definite); sample(pose, u, seed=0, n=None)
-> a draw of the exact transition (3,), or n draws (n, 3) from the streams (seed, k).

Example: ``implicit.laser.OdometryModel(0.05, 0.05, 0.05, 0.05).predict([0, 0, 0], [1, 0, 0])``
)doc";

void bind_odometry(py::module_& m) {
  py::class_<robot::OdometryModel>(m, "OdometryModel", kOdometryDoc)
      .def(py::init([](const py::object& a1, const py::object& a2, const py::object& a3,
                       const py::object& a4) {
             return robot::OdometryModel(
                 {number_arg(a1, "alpha1", 0.0, kInf), number_arg(a2, "alpha2", 0.0, kInf),
                  number_arg(a3, "alpha3", 0.0, kInf), number_arg(a4, "alpha4", 0.0, kInf)});
           }),
           py::arg("alpha1") = 0.2, py::arg("alpha2") = 0.2, py::arg("alpha3") = 0.2,
           py::arg("alpha4") = 0.2)
      .def_property_readonly("alphas",
                             [](const robot::OdometryModel& o) {
                               const robot::OdometryAlphas& a = o.alphas();
                               return py::make_tuple(a.alpha1, a.alpha2, a.alpha3, a.alpha4);
                             })
      .def(
          "predict",
          [](const robot::OdometryModel& o, const py::object& pose, const py::object& u) {
            return numpy_vec3(o.predict(vec3_arg(pose, "pose"), vec3_arg(u, "u")));
          },
          py::arg("pose"), py::arg("u"), "pose ⊕ u: where the odometry says the robot went.")
      .def(
          "covariance",
          [](const robot::OdometryModel& o, const py::object& pose, const py::object& u) {
            return numpy_mat3(o.process_covariance(vec3_arg(pose, "pose"), vec3_arg(u, "u")));
          },
          py::arg("pose"), py::arg("u"),
          "J diag(var_rot1, var_trans, var_rot2) J^T + diag(floor^2) (3, 3).")
      .def(
          "sample",
          [](const robot::OdometryModel& o, const py::object& pose, const py::object& u,
             const py::object& seed, const py::object& n) -> py::object {
            const Pose x = vec3_arg(pose, "pose");
            const Vec<3> du = vec3_arg(u, "u");
            const auto s = seed_arg(seed, "seed");
            if (n.is_none()) {
              Rng rng({s, 0, 0, purpose::kProposal});
              return numpy_vec3(o.sample(x, du, rng));
            }
            const auto count = static_cast<std::size_t>(int_arg(n, "n", 0, 100'000'000));
            std::vector<Pose> draws(count);
            for (std::size_t k = 0; k < count; ++k) {
              Rng rng({s, 0, k, purpose::kProposal});
              draws[k] = o.sample(x, du, rng);
            }
            return numpy_poses(draws);
          },
          py::arg("pose"), py::arg("u"), py::arg("seed") = 0, py::arg("n") = py::none(),
          "Draws of the exact transition (nav2's sampler): (3,), or (n, 3) when n is given.")
      .def("__repr__", [](const robot::OdometryModel& o) {
        const robot::OdometryAlphas& a = o.alphas();
        return fmt::format("OdometryModel(alpha1={}, alpha2={}, alpha3={}, alpha4={})", a.alpha1,
                           a.alpha2, a.alpha3, a.alpha4);
      });
}

}  // namespace

py::dict carmen_log_dict(const robot::CarmenLog& log) { return carmen_dict(log); }

}  // namespace implicit::python::laser

namespace implicit::python {

void init_laser(py::module_& m) {
  laser::bind_grid(m);
  laser::bind_files(m);
  laser::bind_mapping(m);
  laser::bind_field(m);
  laser::bind_beam(m);
  laser::bind_odometry(m);
  laser::init_laser_filter(m);
}

}  // namespace implicit::python
