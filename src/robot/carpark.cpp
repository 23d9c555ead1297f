#include "implicit/robot/carpark.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

std::vector<std::string> beam_header(const char* first, const char* prefix, const char* suffix) {
  std::vector<std::string> h{first};
  for (int k = 0; k < kCarParkBeams; ++k) h.push_back(fmt::format("{}{}{}", prefix, k, suffix));
  return h;
}

}  // namespace

std::filesystem::path default_carpark_dir() {
  return find_share_dir("data", "IMPLICIT_DATA_DIR") / "carpark";
}

CarParkData load_carpark(const std::filesystem::path& dir) {
  CarParkData d;
  {
    const auto t =
        read_numeric_csv(dir / "carpark_dr.csv", {"time_s", "speed_mps", "steering_rad"});
    require_increasing(t, 0);
    for (std::size_t r = 0; r < t.rows; ++r) {
      d.control_time.push_back(t.at(r, 0));
      d.encoder_speed.push_back(t.at(r, 1));
      const double alpha = t.at(r, 2);
      if (!(std::abs(alpha) < 1.2))  // tan(alpha) H / L must stay below 1
        throw ParseError(
            fmt::format("{}:{}: field 'steering_rad': expected |steering| < 1.2 rad, "
                        "got {}",
                        t.file, t.line_of(r), alpha));
      d.steering.push_back(alpha);
    }
  }
  {
    const auto t = read_numeric_csv(dir / "carpark_gps.csv", {"time_s", "east_m", "north_m"});
    require_increasing(t, 0);
    for (std::size_t r = 0; r < t.rows; ++r) {
      d.gps_time.push_back(t.at(r, 0));
      d.gps.emplace_back(t.at(r, 1), t.at(r, 2));
    }
  }
  {
    const auto t = read_numeric_csv(dir / "carpark_beacons.csv", {"id", "east_m", "north_m"});
    for (std::size_t r = 0; r < t.rows; ++r) {
      const double id = t.at(r, 0);
      // Bounded before the conversion to int (converting a larger double is undefined).
      if (id != std::floor(id) || id < 0 || id > std::numeric_limits<int>::max() ||
          d.beacons.index_of(static_cast<int>(id)) >= 0)
        throw ParseError(
            fmt::format("{}:{}: field 'id': expected a new integer id in [0, {}], got {}", t.file,
                        t.line_of(r), std::numeric_limits<int>::max(), id));
      d.beacons.add(static_cast<int>(id), Landmark(t.at(r, 1), t.at(r, 2)));
    }
  }
  {
    const auto range =
        read_numeric_csv(dir / "carpark_laser_range_cm.csv", beam_header("time_s", "r", "_cm"));
    const auto inten =
        read_numeric_csv(dir / "carpark_laser_intensity.csv", beam_header("time_s", "i", ""));
    require_increasing(range, 0);
    if (range.rows != inten.rows)
      throw ParseError(fmt::format("{}: expected {} scans (as in {}), got {}", inten.file,
                                   range.rows, range.file, inten.rows));
    d.scans.resize(range.rows);
    for (std::size_t r = 0; r < range.rows; ++r) {
      if (range.at(r, 0) != inten.at(r, 0))
        throw ParseError(
            fmt::format("{}:{}: field 'time_s': expected {} (the time of the same "
                        "scan in {}), got {}",
                        inten.file, inten.line_of(r), range.at(r, 0), range.file, inten.at(r, 0)));
      CarParkScan& s = d.scans[r];
      s.time = range.at(r, 0);
      for (int k = 0; k < kCarParkBeams; ++k) {
        const double cm = range.at(r, static_cast<std::size_t>(k) + 1);
        const double in = inten.at(r, static_cast<std::size_t>(k) + 1);
        if (cm < 0)
          throw ParseError(fmt::format("{}:{}: field 'r{}_cm': expected a range >= 0, got {}",
                                       range.file, range.line_of(r), k, cm));
        if (in < 0)
          throw ParseError(fmt::format("{}:{}: field 'i{}': expected an intensity >= 0, got {}",
                                       inten.file, inten.line_of(r), k, in));
        s.range[static_cast<std::size_t>(k)] = cm / 100.0;
        s.intensity[static_cast<std::size_t>(k)] = in;
      }
    }
  }
  return d;
}

std::vector<Measurement> extract_beacon_detections(std::span<const double> range,
                                                   std::span<const double> intensity) {
  require(range.size() == intensity.size(),
          "beacon extraction: expected as many intensities as ranges ({}), got {}", range.size(),
          intensity.size());
  std::vector<Measurement> out;
  const double deg = kPi / 180.0;
  std::size_t k = 0;
  while (k < range.size()) {
    if (!(intensity[k] > 0)) {
      ++k;
      continue;
    }
    double sum_r = 0.0, sum_b = 0.0;
    std::size_t n = 0;
    for (; k < range.size() && intensity[k] > 0; ++k, ++n) {
      sum_r += range[k];
      sum_b += 0.5 * static_cast<double>(k) * deg;
    }
    out.emplace_back(sum_r / static_cast<double>(n), sum_b / static_cast<double>(n));
  }
  return out;
}

RobotLog carpark_to_log(const CarParkData& data, const UteModel& model,
                        const CarParkOptions& options) {
  RobotLog log;
  log.vehicle = declare_vehicle(model.params());
  log.landmarks = data.beacons;
  log.initial = PosePrior{options.start_time, options.initial_pose, options.initial_std};
  for (std::size_t k = 0; k < data.control_time.size(); ++k) {
    const double alpha = data.steering[k];
    log.controls.push_back(
        {data.control_time[k], Control(model.axle_speed(data.encoder_speed[k], alpha), alpha)});
  }
  for (const CarParkScan& s : data.scans) {
    ObservationSet set;
    set.time = s.time;
    for (const Measurement& z : extract_beacon_detections(s.range, s.intensity))
      set.observations.push_back({z, -1});
    log.scans.push_back(std::move(set));
  }
  // Heading reference from the GPS track: the laser point moves in direction
  // beta + atan2(a t, 1 - b t), t = tan(alpha)/L (spec §3.1, g_xy = Rot(beta)(1 - b t, a t)).
  const UteParams& p = model.params();
  const std::size_t n = data.gps.size();
  for (std::size_t k = 0; k < n; ++k) {
    TruthRecord r;
    r.time = data.gps_time[k];
    r.position = data.gps[k];
    if (n >= 3) {
      const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? n - 1 : k + 1;
      const Vec<2> v = (data.gps[b] - data.gps[a]) / (data.gps_time[b] - data.gps_time[a]);
      if (v.norm() > options.heading_min_speed) {
        // Steering at the fix time: nearest control record.
        auto it = std::lower_bound(data.control_time.begin(), data.control_time.end(), r.time);
        if (it == data.control_time.end()) --it;
        const double alpha =
            data.steering[static_cast<std::size_t>(it - data.control_time.begin())];
        const double t = std::tan(alpha) / p.wheelbase;
        r.heading =
            std::atan2(v(1), v(0)) - std::atan2(p.laser_forward * t, 1.0 - p.laser_left * t);
      }
    }
    log.truth.push_back(r);
  }
  return log;
}

std::vector<Pose> dead_reckoning(const UteModel& model, const Pose& initial,
                                 const StepSchedule& schedule) {
  std::vector<Pose> poses;
  poses.reserve(schedule.steps.size());
  Pose x = initial;
  for (const FilterStep& s : schedule.steps) {
    x = model.predict(x, s.u);
    poses.push_back(x);
  }
  return poses;
}

std::vector<DetectionResidual> detection_residuals(const RobotLog& log,
                                                   const StepSchedule& schedule,
                                                   std::span<const Pose> poses) {
  require(poses.size() == schedule.steps.size(),
          "detection residuals: expected one pose per step ({}), got {}", schedule.steps.size(),
          poses.size());
  std::vector<DetectionResidual> out;
  for (std::size_t n = 0; n < schedule.steps.size(); ++n) {
    const int scan = schedule.steps[n].scan;
    if (scan < 0) continue;
    for (const Observation& o : log.scans[static_cast<std::size_t>(scan)].observations) {
      DetectionResidual d;
      d.time = log.scans[static_cast<std::size_t>(scan)].time;
      d.scan = scan;
      d.z = o.z;
      d.world = RangeBearingSensor::inverse(poses[n], o.z);
      d.distance = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < log.landmarks.size(); ++k) {
        const double dist = (log.landmarks.position(k) - d.world).norm();
        if (dist < d.distance) {
          d.distance = dist;
          d.nearest_beacon = static_cast<int>(k);
        }
      }
      out.push_back(d);
    }
  }
  return out;
}

}  // namespace implicit::robot
