// Tracks of a robot log at given times: ground truth and odometry, interpolated between records.
#include <algorithm>
#include <limits>

#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/log_format.hpp"

namespace implicit::robot {

TruthTrack interpolate_truth(const RobotLog& log, const StepSchedule& schedule, double max_gap) {
  std::vector<double> times;
  times.reserve(schedule.steps.size());
  for (const FilterStep& step : schedule.steps) times.push_back(step.time);
  return interpolate_truth(log, times, max_gap);
}

TruthTrack interpolate_truth(const RobotLog& log, const std::vector<double>& times,
                             double max_gap) {
  require(max_gap > 0.0, "interpolate_truth: expected a positive maximum gap, got {} s", max_gap);
  TruthTrack track;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto& tr = log.truth;
  for (const double t : times) {
    Vec<2> p(nan, nan);
    double h = nan;
    if (!tr.empty() && t >= tr.front().time && t <= tr.back().time) {
      auto it = std::lower_bound(tr.begin(), tr.end(), t,
                                 [](const TruthRecord& r, double v) { return r.time < v; });
      if (it->time == t) {
        p = it->position;
        if (it->heading) h = *it->heading;
      } else {
        const TruthRecord& b = *it;
        const TruthRecord& a = *(it - 1);
        if (b.time - a.time <= max_gap) {
          const double s = (t - a.time) / (b.time - a.time);
          p = (1.0 - s) * a.position + s * b.position;
          if (a.heading && b.heading) h = *a.heading + s * wrap_angle(*b.heading - *a.heading);
        }
      }
    }
    track.position.push_back(p);
    track.heading.push_back(h);
  }
  return track;
}

std::vector<Pose> interpolate_odometry(const RobotLog& log, const std::vector<double>& times) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto& od = log.odometry;
  std::vector<Pose> poses;
  poses.reserve(times.size());
  for (const double t : times) {
    if (od.empty() || !(t >= od.front().time && t <= od.back().time)) {
      poses.emplace_back(nan, nan, nan);
      continue;
    }
    auto it = std::lower_bound(od.begin(), od.end(), t,
                               [](const OdometryRecord& r, double v) { return r.time < v; });
    if (it->time == t) {
      poses.push_back(it->pose);
      continue;
    }
    const OdometryRecord &a = *(it - 1), &b = *it;
    const double s = (t - a.time) / (b.time - a.time);
    const Vec<2> p = (1.0 - s) * a.pose.head<2>() + s * b.pose.head<2>();
    poses.emplace_back(p(0), p(1), a.pose(2) + s * wrap_angle(b.pose(2) - a.pose(2)));
  }
  return poses;
}

}  // namespace implicit::robot
