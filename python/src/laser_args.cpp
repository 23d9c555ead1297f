// Argument conversion of the laser bindings (laser.hpp): Python objects in, checked C++ values
// out, and an InvalidArgument naming the argument for anything else. pybind11's own conversions
// would raise a TypeError listing the whole signature instead of the argument at fault.
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "laser.hpp"

namespace implicit::python::laser {

namespace {

/// Checks a scan's fields; prefix names where the scan came from ("" or "scans[3].").
void check_scan(const robot::LaserScan& s, const std::string& prefix) {
  require(!s.ranges.empty(), "{}ranges: expected at least one beam, got none", prefix);
  for (std::size_t i = 0; i < s.ranges.size(); ++i)
    require(!std::isnan(s.ranges[i]) && s.ranges[i] >= 0,
            "{}ranges: expected ranges >= 0 [m] (+inf: no return), got {} at index {}", prefix,
            s.ranges[i], i);
  require(std::isfinite(s.angle_min), "{}angle_min: expected a finite number [rad], got {}", prefix,
          s.angle_min);
  require(std::isfinite(s.angle_increment) && s.angle_increment != 0,
          "{}angle_increment: expected a finite non-zero number [rad], got {}", prefix,
          s.angle_increment);
  require(std::isfinite(s.range_min) && s.range_min >= 0,
          "{}range_min: expected a finite number >= 0 [m], got {}", prefix, s.range_min);
  require(std::isfinite(s.range_max) && s.range_max > s.range_min,
          "{}range_max: expected a finite number > range_min = {} [m], got {}", prefix, s.range_min,
          s.range_max);
}

}  // namespace

Vec<3> vec3_arg(const py::handle& o, const std::string& name) {
  const Array a = require_shape(o, name, {3});
  return {a.data()[0], a.data()[1], a.data()[2]};
}

robot::LaserMount mount_arg(const py::handle& o, const std::string& name) {
  const Vec<3> m = vec3_arg(o, name);
  return {m(0), m(1), m(2)};
}

const robot::OccupancyGrid& grid_arg(const py::handle& o, const std::string& name) {
  require(py::isinstance<robot::OccupancyGrid>(o),
          "{}: expected an implicit.laser.OccupancyGrid, got {}", name, type_name(o));
  return o.cast<const robot::OccupancyGrid&>();
}

robot::OdometryAlphas alphas_arg(const py::handle& o, const std::string& name) {
  const Array a = require_shape(o, name, {4});
  for (py::ssize_t k = 0; k < 4; ++k)
    require(a.data()[k] >= 0, "{}: expected alpha1..alpha4 >= 0, got {} at index {}", name,
            a.data()[k], k);
  return {a.data()[0], a.data()[1], a.data()[2], a.data()[3]};
}

robot::LaserScan scan_arg(const py::handle& ranges, const py::handle& angle_min,
                          const py::handle& angle_increment, const py::handle& range_min,
                          const py::handle& range_max, const std::string& prefix) {
  robot::LaserScan s;
  const Array r = require_shape(ranges, prefix + "ranges", {-1}, /*finite=*/false);
  s.ranges.assign(r.data(), r.data() + r.size());
  s.angle_min = number_arg(angle_min, prefix + "angle_min", -kInf, kInf);
  s.angle_increment = number_arg(angle_increment, prefix + "angle_increment", -kInf, kInf);
  s.range_min = number_arg(range_min, prefix + "range_min", 0.0, kInf);
  s.range_max = number_arg(range_max, prefix + "range_max", 0.0, kInf, true);
  check_scan(s, prefix);
  return s;
}

std::vector<robot::LaserScan> scans_arg(const py::handle& o, const std::string& name) {
  std::vector<robot::LaserScan> scans;
  if (py::isinstance<py::dict>(o)) {
    // read_carmen's layout: per-scan arrays, ranges a 2-D array or a list of 1-D arrays.
    const auto d = py::reinterpret_borrow<py::dict>(o);
    for (const char* key : {"ranges", "angle_min", "angle_increment", "range_max"})
      require(d.contains(key),
              "{}: expected the key '{}' (per-scan arrays, as read_carmen returns them), got "
              "none",
              name, key);
    const py::object ranges = d["ranges"];
    require(py::isinstance<py::array>(ranges) || py::isinstance<py::list>(ranges) ||
                py::isinstance<py::tuple>(ranges),
            "{}['ranges']: expected a 2-D array or a list of arrays, got {}", name,
            type_name(ranges));
    const auto n = static_cast<py::ssize_t>(py::len(ranges));
    const Array a0 = require_shape(d["angle_min"], name + "['angle_min']", {n});
    const Array da = require_shape(d["angle_increment"], name + "['angle_increment']", {n});
    const Array r1 = require_shape(d["range_max"], name + "['range_max']", {n});
    std::vector<double> r0(static_cast<std::size_t>(n), 0.0);  // range_min: 0 unless given
    if (d.contains("range_min")) {
      const Array a = require_shape(d["range_min"], name + "['range_min']", {n});
      r0.assign(a.data(), a.data() + n);
    }
    for (py::ssize_t k = 0; k < n; ++k) {
      const std::string at = fmt::format("{}[{}].", name, k);
      const Array r = require_shape(ranges[py::int_(k)], at + "ranges", {-1}, false);
      robot::LaserScan s;
      s.ranges.assign(r.data(), r.data() + r.size());
      s.angle_min = a0.data()[k];
      s.angle_increment = da.data()[k];
      s.range_min = r0[static_cast<std::size_t>(k)];
      s.range_max = r1.data()[k];
      check_scan(s, at);
      scans.push_back(std::move(s));
    }
    return scans;
  }
  require(py::isinstance<py::list>(o) || py::isinstance<py::tuple>(o),
          "{}: expected the dict of read_carmen or a list of scan dicts, got {}", name,
          type_name(o));
  const auto seq = py::reinterpret_borrow<py::sequence>(o);
  for (std::size_t k = 0; k < seq.size(); ++k) {
    const std::string at = fmt::format("{}[{}]", name, k);
    const py::object item = seq[k];
    require(py::isinstance<py::dict>(item),
            "{}: expected a dict with ranges, angle_min, angle_increment, range_max, got {}", at,
            type_name(item));
    const auto s = py::reinterpret_borrow<py::dict>(item);
    const auto field = [&](const char* key) -> py::object {
      require(s.contains(key), "{}: expected the key '{}', got none", at, key);
      return s[key];
    };
    scans.push_back(scan_arg(field("ranges"), field("angle_min"), field("angle_increment"),
                             s.contains("range_min") ? py::object(s["range_min"]) : py::float_(0.0),
                             field("range_max"), at + "."));
  }
  return scans;
}

robot::Interpolation interpolation_arg(const py::handle& o, const std::string& name) {
  const std::string s = choice_arg(o, name, {"nearest", "bilinear", "bicubic"});
  return s == "nearest"    ? robot::Interpolation::kNearest
         : s == "bilinear" ? robot::Interpolation::kBilinear
                           : robot::Interpolation::kBicubic;
}

robot::BeamAggregation aggregation_arg(const py::handle& o, const std::string& name) {
  return choice_arg(o, name, {"product", "cubed-sum"}) == "product"
             ? robot::BeamAggregation::kProduct
             : robot::BeamAggregation::kCubedSum;
}

const char* const kLaserKeywords =
    "z_hit, z_rand, sigma_hit, max_dist, max_beams, interpolation, aggregation, mount";

LaserSpec laser_spec(const py::dict& kw, const std::string& where) {
  LaserSpec spec;
  robot::LikelihoodFieldParams& p = spec.params;
  for (const auto& item : kw) {
    const std::string key = py::str(item.first);
    const py::handle v = item.second;
    if (key == "z_hit")
      p.z_hit = number_arg(v, key, 0.0, kInf, true);
    else if (key == "z_rand")
      p.z_rand = number_arg(v, key, 0.0, kInf);
    else if (key == "sigma_hit")
      p.sigma_hit = number_arg(v, key, 0.0, kInf, true);
    else if (key == "max_dist")
      p.laser_likelihood_max_dist = number_arg(v, key, 0.0, kInf, true);
    else if (key == "max_beams")
      p.max_beams = static_cast<int>(int_arg(v, key, 1, 1'000'000));
    else if (key == "interpolation")
      p.interpolation = interpolation_arg(v, key);
    else if (key == "aggregation")
      p.aggregation = aggregation_arg(v, key);
    else if (key == "mount")
      spec.mount = mount_arg(v, key);
    else
      throw InvalidArgument(fmt::format("{}: unknown keyword '{}' (expected one of {})", where,
                                        printable(key), kLaserKeywords));
  }
  return spec;
}

}  // namespace implicit::python::laser
