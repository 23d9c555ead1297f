// The g2o graph of a landmark SLAM run (landmark_slam.hpp, slam_pose_graph; docs/formats.md,
// "Landmark SLAM: motion edges, landmarks and their observations").
#include <algorithm>
#include <cstddef>
#include <vector>

#include "experiments/landmark_slam.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/pose_graph.hpp"
#include "implicit/robot/range_bearing.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::experiments {
namespace {

/// ML association after the fact: the landmark whose predicted detection from `pose` is nearest
/// z in the sensor covariance's metric, if inside the gate; else landmarks.size().
std::size_t slam_graph_nearest_landmark(const robot::RangeBearingSensor& sensor, double gate_chi2,
                                        const slam::Pose& pose,
                                        const std::vector<slam::Landmark>& landmarks,
                                        const slam::Measurement& z) {
  const Mat<2> info = sensor.noise_covariance().inverse();
  std::size_t best = landmarks.size();
  double best_d2 = gate_chi2;
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    const Vec<2> e = robot::RangeBearingSensor::residual(sensor.predict(pose, landmarks[k]), z);
    const double d2 = e.dot(info * e);
    if (d2 <= best_d2) {
      best_d2 = d2;
      best = k;
    }
  }
  return best;
}

}  // namespace

SlamPoseGraph slam_pose_graph(const slam::SlamDataset& d, const slam::SlamRun& run,
                              const slam::SlamOptions& options) {
  require(run.path.size() == d.steps() + 1,
          "slam --g2o: expected a path of {} poses (run 0's), got {}", d.steps() + 1,
          run.path.size());
  const robot::AnyMotionModel motion =
      options.model ? *options.model : robot::AnyMotionModel(robot::UteModel(options.motion));
  SlamPoseGraph out;
  robot::PoseGraph2& g = out.graph;
  g.poses = run.path;
  g.landmarks = run.map.landmarks;
  g.edges.reserve(d.steps());
  for (std::size_t n = 1; n <= d.steps(); ++n) {
    const robot::AnyMotionModel m = motion.with_dt(d.step_length(n));
    const slam::Pose& from = run.path[n - 1];
    const slam::Pose z = robot::between(from, m.predict(from, d.control(n)));
    g.edges.push_back(
        {n - 1, n, z,
         robot::world_noise_edge_information(m.process_covariance(from, d.control(n)), from, z)});
  }
  const bool known = options.association == slam::Association::kKnown;
  const Mat<2>& sigma2 = options.sensor.noise_covariance();
  for (std::size_t n = 1; n <= d.steps(); ++n)
    for (const slam::Observation& o : d.observations(n)) {
      if (o.z(0) < options.min_range) continue;  // the filter ignored it too
      std::size_t k = g.landmarks.size();
      if (known) {
        const auto it = std::find(run.map.ids.begin(), run.map.ids.end(), o.landmark);
        k = static_cast<std::size_t>(it - run.map.ids.begin());
      } else {
        k = slam_graph_nearest_landmark(options.sensor, options.gate_chi2, run.path[n], g.landmarks,
                                        o.z);
      }
      if (k == g.landmarks.size()) {
        ++out.unassociated;
        continue;
      }
      g.point_edges.push_back(robot::range_bearing_point_edge(n, k, o.z, sigma2));
    }
  return out;
}

}  // namespace implicit::experiments
