// implicit.slam._grid: grid SLAM on a CARMEN laser log (slam::run_grid_slam, spec §3.13), the run
// of `implicit slam --sensor laser` with one seed. The settings are checked against the ranges of
// the tool's flags (apps/cmd_slam_laser.cpp), so a value the command line refuses is refused here
// too, naming the keyword; the result is a dict of numpy arrays (the trajectories and the map).

#include <Python.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "experiments/choices.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "laser.hpp"

namespace implicit::python::grid_slam {
namespace {

using laser::kInf;

// The ranges of the tool's flags: -M in_range(1, 1000000), --alphas in_range(0, 10) each,
// --max-scans in_range(0, 100000000), --threads in_range(0, 1024) (apps/cmd_slam.cpp,
// cmd_slam_laser.cpp, context.cpp).
constexpr long long kMaxParticles = 1'000'000;
constexpr double kMaxAlpha = 10.0;
constexpr long long kMaxScans = 100'000'000;
constexpr long long kMaxThreads = 1024;

/// The keyword `key` of the settings the Python wrapper passes (python/implicit/slam.py).
py::object setting(const py::dict& kw, const char* key) {
  require(kw.contains(key), "grid: missing setting '{}'", key);
  return kw[key];
}

robot::OdometryAlphas grid_alphas(const py::handle& o) {
  const Array a = require_shape(o, "alphas", {4}, /*finite=*/false);
  double v[4];
  for (py::ssize_t k = 0; k < 4; ++k)
    v[k] = number_arg(py::float_(a.data()[k]), fmt::format("alphas[{}]", k), 0.0, kMaxAlpha);
  return {v[0], v[1], v[2], v[3]};
}

/// A log from the dict of implicit.laser.read_carmen: the scans with their times and the
/// laser's poses (the other keys are not used by the run).
robot::CarmenLog log_from_dict(const py::dict& d) {
  robot::CarmenLog log;
  log.scans = laser::scans_arg(d, "data");
  const auto n = static_cast<py::ssize_t>(log.scans.size());
  for (const char* key : {"times", "laser_poses"})
    require(d.contains(key), "data: expected the key '{}' (as read_carmen returns it), got none",
            key);
  const Array times = require_shape(d["times"], "data['times']", {n});
  const Array poses = require_shape(d["laser_poses"], "data['laser_poses']", {n, 3});
  for (py::ssize_t k = 0; k < n; ++k) {
    log.scans[static_cast<std::size_t>(k)].time = times.data()[k];
    log.laser_poses.emplace_back(poses.at(k, 0), poses.at(k, 1), poses.at(k, 2));
  }
  log.source = d.contains("source") && py::isinstance<py::str>(d["source"])
                   ? d["source"].cast<std::string>()
                   : std::string("data");
  require(!log.scans.empty(), "data: expected at least one scan, got none");
  return log;
}

py::array_t<double> pose_rows(const std::vector<slam::GridSlamPose>& poses) {
  py::array_t<double> a({static_cast<py::ssize_t>(poses.size()), py::ssize_t{3}});
  for (std::size_t k = 0; k < poses.size(); ++k)
    for (int i = 0; i < 3; ++i) a.mutable_at(k, i) = poses[k].pose(i);
  return a;
}

py::array_t<double> pose_times(const std::vector<slam::GridSlamPose>& poses) {
  py::array_t<double> a(static_cast<py::ssize_t>(poses.size()));
  for (std::size_t k = 0; k < poses.size(); ++k) a.mutable_at(k) = poses[k].time;
  return a;
}

/// The map's cells (height, width), row 0 the lowest y, as OccupancyGrid.cells.
py::array_t<std::int8_t> map_cells(const robot::OccupancyGrid& g) {
  py::array_t<std::int8_t> a(
      {static_cast<py::ssize_t>(g.height()), static_cast<py::ssize_t>(g.width())});
  std::copy(g.data().begin(), g.data().end(), a.mutable_data());
  return a;
}

py::object optional_number(const std::optional<double>& v) {
  return v ? py::object(py::float_(*v)) : py::object(py::none());
}

/// The map score of spec §3.13.5 under the keys of the tool's JSON (`prefix` "odometry_" for the
/// dead-reckoning map's); None for a fraction with nothing to count, or when not scored.
void add_map_score(py::dict& d, const std::optional<robot::MapComparison>& s,
                   const std::string& prefix) {
  d[(prefix + "map_agreement").c_str()] = s ? optional_number(s->agreement) : py::none();
  d[(prefix + "map_occupied_precision").c_str()] =
      s ? optional_number(s->occupied_precision) : py::none();
  d[(prefix + "map_occupied_recall").c_str()] =
      s ? optional_number(s->occupied_recall) : py::none();
  d[(prefix + "map_f1").c_str()] = s ? optional_number(s->occupied_f1) : py::none();
}

py::dict result_dict(const slam::GridSlamRun& run, const slam::GridSlamRunOptions& o,
                     const std::string& method, const std::string& source) {
  py::dict d;
  d["data"] = source;
  d["method"] = method;
  d["particles"] = o.filter.particles;
  d["seed"] = o.filter.seed;
  d["map_min_echoes"] = o.filter.map.min_echoes;
  const robot::OdometryAlphas& a = o.filter.alphas;
  d["alphas"] = py::make_tuple(a.alpha1, a.alpha2, a.alpha3, a.alpha4);
  d["scans_processed"] = run.processed;
  d["times"] = pose_times(run.trajectory);
  d["trajectory"] = pose_rows(run.trajectory);
  d["reference"] = pose_rows(run.reference);
  d["map"] = map_cells(run.map);
  d["resolution"] = run.map.resolution();
  d["origin"] = py::make_tuple(run.map.origin()(0), run.map.origin()(1));
  // The same map as an OccupancyGrid, for save_map and the laser models (None: nothing seen).
  d["grid"] = run.map.empty() ? py::object(py::none()) : py::cast(run.map);
  d["relation_translation_m"] = run.relations.translation_mean;
  d["relation_rotation_deg"] = run.relations.rotation_mean_deg;
  d["odometry_relation_translation_m"] = run.odometry_relations.translation_mean;
  d["odometry_relation_rotation_deg"] = run.odometry_relations.rotation_mean_deg;
  d["ate_m"] = optional_number(run.ate_m);
  d["odometry_ate_m"] = optional_number(run.odometry_ate_m);
  add_map_score(d, run.map_score, "");
  add_map_score(d, run.odometry_map_score, "odometry_");
  d["map_tolerance_m"] =
      run.map_score ? py::object(py::float_(run.map_score->tolerance_m)) : py::object(py::none());
  d["reference_map_cpu_s"] = run.reference_map_cpu_seconds;
  d["map_score_cpu_s"] = run.map_score_cpu_seconds;
  d["cpu_seconds"] = run.cpu_seconds;
  d["resamplings"] = run.resamplings;
  d["ess_fraction"] = run.mean_ess;
  d["evaluations_per_particle_and_scan"] = run.mean_evaluations;
  d["fallbacks"] = run.fallbacks;
  d["failures"] = run.failures;
  return d;
}

py::dict grid(const py::dict& kw, const py::object& progress) {
  // Every setting is checked before the log is read: a long read must not end in a typing error.
  const py::object data = setting(kw, "data");
  const bool from_dict = py::isinstance<py::dict>(data);
  const std::filesystem::path file = from_dict ? std::filesystem::path() : path_arg(data, "data");
  const std::string method =
      choice_arg(setting(kw, "method"), "method", experiments::grid_slam_methods().names());
  slam::GridSlamRunOptions o;
  o.proposal = slam::parse_grid_proposal(method);
  o.filter.particles =
      static_cast<std::size_t>(int_arg(setting(kw, "particles"), "particles", 1, kMaxParticles));
  o.filter.seed = seed_arg(setting(kw, "seed"), "seed");
  o.data_seed = o.filter.seed;  // as the tool's run with --seed: the odometry's noise too
  o.filter.alphas = grid_alphas(setting(kw, "alphas"));
  o.max_scans =
      static_cast<std::size_t>(int_arg(setting(kw, "max_scans"), "max_scans", 0, kMaxScans));
  o.filter.map.min_echoes =
      static_cast<int>(int_arg(setting(kw, "map_min_echoes"), "map_min_echoes", 0, 255));
  const int threads = static_cast<int>(int_arg(setting(kw, "threads"), "threads", 0, kMaxThreads));
  require(progress.is_none() || PyCallable_Check(progress.ptr()),
          "progress: expected a callable progress(done, total) or None, got {}",
          type_name(progress));
  o.validate();
  robot::CarmenLog log;
  if (from_dict) {
    log = log_from_dict(py::reinterpret_borrow<py::dict>(data));
  } else {
    py::gil_scoped_release unlocked;
    log = robot::read_carmen(file);
  }
  // Called after each scan the filter steps on, with the interpreter's lock: the user's
  // callback, and Ctrl-C. An exception thrown there unwinds the run and reaches the caller.
  o.on_step = [&progress](std::size_t done, std::size_t total) {
    py::gil_scoped_acquire locked;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!progress.is_none()) progress(done, total);
  };
  slam::GridSlamRun run;
  {
    py::gil_scoped_release unlocked;
    ThreadLimit limit(threads);
    run = slam::run_grid_slam(log, o);
  }
  return result_dict(run, o, method, log.source);
}

}  // namespace
}  // namespace implicit::python::grid_slam

namespace implicit::python {

void init_grid_slam(py::module_& m) {
  m.def("_grid", &grid_slam::grid, py::arg("settings"), py::arg("progress") = py::none(),
        "Grid SLAM on a CARMEN laser log, one run of `implicit slam --sensor laser` (use "
        "implicit.slam.grid).");
}

}  // namespace implicit::python
