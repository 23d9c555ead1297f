// implicit.eval: APE and RPE of trajectories given as numpy arrays, with the library's definitions
// (implicit/robot/trajectory_metrics.hpp), the numbers of `implicit eval`.

#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "common.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/trajectory_metrics.hpp"

namespace implicit::python {
namespace {

/// Rows (t, x, y, heading) or (t, x, y, z, qx, qy, qz, qw) as a trajectory; every row checked, the
/// message naming the argument and the row.
robot::Trajectory eval_py_trajectory(const py::handle& o, const std::string& name) {
  const Array a = require_shape(o, name, {-1, -1});
  const py::ssize_t cols = a.shape(1);
  require(cols == 4 || cols == 8,
          "{}: expected shape (n, 4) (rows t, x, y, heading) or (n, 8) (rows t, x, y, z, qx, qy, "
          "qz, qw), got shape {}",
          name, shape_text(a));
  require(a.shape(0) > 0, "{}: expected at least one pose, got none", name);
  robot::Trajectory t;
  t.source = name;
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    const double* r = a.data() + i * cols;
    require(i == 0 || r[0] > t.times.back(),
            "{}: row {}: expected a time after {} (times must increase), got {}", name, i,
            i == 0 ? 0.0 : t.times.back(), r[0]);
    robot::Pose3 p;
    if (cols == 4) {
      p = robot::Pose3::from_se2(robot::Pose(r[1], r[2], r[3]));
    } else {
      p.translation = Vec<3>(r[1], r[2], r[3]);
      p.rotation = Eigen::Quaterniond(r[7], r[4], r[5], r[6]);
      const double norm = p.rotation.norm();
      require(std::abs(norm - 1.0) <= 1e-3,
              "{}: row {}: expected a unit quaternion (qx, qy, qz, qw with norm within 1e-3 of 1), "
              "got norm {}",
              name, i, norm);
      p.rotation.normalize();
    }
    t.times.push_back(r[0]);
    t.poses.push_back(p);
  }
  return t;
}

py::dict eval_py_stats(const std::vector<double>& v, const robot::StatisticsOptions& o) {
  const robot::ErrorStatistics s = robot::error_statistics(v, o);
  py::dict d;
  d["count"] = s.count;
  d["mean"] = s.mean;
  d["median"] = s.median;
  d["rmse"] = s.rmse;
  d["max"] = s.max;
  d["min"] = s.min;
  d["std"] = s.std;
  d["mean_ci"] = py::make_tuple(s.mean_lo, s.mean_hi);
  d["rmse_ci"] = py::make_tuple(s.rmse_lo, s.rmse_hi);
  return d;
}

struct EvalPyInput {
  robot::PosePairs pairs;
  robot::Alignment alignment;
  robot::StatisticsOptions stats;
};

EvalPyInput eval_py_prepare(const py::handle& ref, const py::handle& est, const py::handle& align,
                            const py::handle& max_diff, const py::handle& offset,
                            const py::handle& seed) {
  const std::string kind = choice_arg(align, "align", {"none", "se2", "se3", "sim3"});
  const robot::TimeAssociationOptions assoc{.max_diff = number_arg(max_diff, "max_diff", 0.0, 1e9),
                                            .offset = number_arg(offset, "offset", -1e12, 1e12)};
  EvalPyInput in;
  in.stats.seed = seed_arg(seed, "seed");
  in.pairs =
      robot::associate(eval_py_trajectory(ref, "ref"), eval_py_trajectory(est, "est"), assoc);
  in.alignment = robot::align_umeyama(in.pairs, robot::alignment_kind_from_string(kind));
  return in;
}

py::dict eval_py_result(const EvalPyInput& in, const robot::TrajectoryErrors& e) {
  py::dict d;
  std::vector<double> first, second;
  for (std::size_t k = 0; k < e.first.size(); ++k) {
    first.push_back(in.pairs.times[e.first[k]]);
    second.push_back(in.pairs.times[e.second[k]]);
  }
  d["pairs"] = in.pairs.size();
  d["t_i"] = adopt_vector(std::move(first));
  d["t_j"] = adopt_vector(std::move(second));
  d["translation_m"] = adopt_vector(std::vector<double>(e.translation));
  d["rotation_deg"] = adopt_vector(std::vector<double>(e.rotation_deg));
  d["full"] = adopt_vector(std::vector<double>(e.full));
  py::dict stats;
  stats["translation_m"] = eval_py_stats(e.translation, in.stats);
  stats["rotation_deg"] = eval_py_stats(e.rotation_deg, in.stats);
  stats["full"] = eval_py_stats(e.full, in.stats);
  d["stats"] = stats;
  const robot::Alignment& a = in.alignment;
  py::dict al;
  al["kind"] = robot::to_string(a.kind);
  py::array_t<double> r({3, 3});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.mutable_at(i, j) = a.rotation(i, j);
  al["rotation"] = r;
  al["translation"] = py::array_t<double>(3, a.translation.data());
  al["scale"] = a.scale;
  d["alignment"] = al;
  return d;
}

}  // namespace

void init_eval(py::module_& m) {
  m.def(
      "_ape",
      [](const py::object& ref, const py::object& est, const py::object& align,
         const py::object& max_diff, const py::object& offset, const py::object& seed) {
        const EvalPyInput in = eval_py_prepare(ref, est, align, max_diff, offset, seed);
        return eval_py_result(in, robot::absolute_pose_error(in.pairs, in.alignment));
      },
      py::arg("ref"), py::arg("est"), py::arg("align"), py::arg("max_diff"), py::arg("offset"),
      py::arg("seed"));
  m.def(
      "_rpe",
      [](const py::object& ref, const py::object& est, const py::object& delta,
         const py::object& delta_unit, const py::object& all_pairs, const py::object& align,
         const py::object& max_diff, const py::object& offset, const py::object& seed) {
        const std::string unit = choice_arg(delta_unit, "delta_unit", {"frames", "m"});
        robot::RpeOptions o;
        o.unit = unit == "m" ? robot::DeltaUnit::kMetres : robot::DeltaUnit::kFrames;
        o.delta = o.unit == robot::DeltaUnit::kFrames
                      ? static_cast<double>(int_arg(delta, "delta", 1, 1000000000))
                      : number_arg(delta, "delta", 0.0, 1e9, true);
        o.all_pairs = bool_arg(all_pairs, "all_pairs");
        const EvalPyInput in = eval_py_prepare(ref, est, align, max_diff, offset, seed);
        return eval_py_result(in, robot::relative_pose_error(in.pairs, in.alignment, o));
      },
      py::arg("ref"), py::arg("est"), py::arg("delta"), py::arg("delta_unit"), py::arg("all_pairs"),
      py::arg("align"), py::arg("max_diff"), py::arg("offset"), py::arg("seed"));
}

}  // namespace implicit::python
