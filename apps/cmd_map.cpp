// `implicit map`: the occupancy grid of a CARMEN laser log, built from the log's recorded poses
// and scans (log-odds mapping with known poses, grid_mapping.hpp) and written as a map_server map
// (PGM and YAML), the map `implicit mcl --sensor laser --map` and `implicit simulate --map` read.
// A ROS bag as --data is first read into the same in-memory log (robot/bag.hpp, the log `implicit
// convert` writes), its poses from --pose-topic (geometry_msgs/PoseStamped, e.g. ground truth or
// a localizer) or, without it, from the raw odometry, which drifts.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "bag_flags.hpp"
#include "context.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/map_io.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct MapCommand {
  std::string data;
  RunContext ctx;            ///< --json, and --out: here the map's YAML FILE
  double resolution = 0.05;  ///< [m]
  double max_range = 40.0;   ///< [m]; 0: each scan's range_max
  int min_echoes = 2;        ///< robot::GridMappingOptions::min_echoes
  BagFlags bag;              ///< a ROS bag as --data: topics and frames
  std::string pose_topic;    ///< a bag's geometry_msgs/PoseStamped topic; empty: its odometry
};

/// The log the map is built from, and where its poses came from.
struct MapInput {
  robot::CarmenLog log;
  std::string poses = "log";            ///< "log" (CARMEN), "odometry" or the pose topic
  std::size_t scans_outside_poses = 0;  ///< a bag's scans outside the poses' time span
};

struct CellCounts {
  std::int64_t occupied = 0, free = 0, unknown = 0;
};

/// Counted as a map_server reader sees the saved map: occupied from 65, free up to 19, the rest
/// (never observed, or in between) unknown.
CellCounts count_cells(const robot::OccupancyGrid& g) {
  CellCounts n;
  for (int iy = 0; iy < g.height(); ++iy)
    for (int ix = 0; ix < g.width(); ++ix) {
      if (g.is_occupied(ix, iy))
        ++n.occupied;
      else if (g.is_free(ix, iy))
        ++n.free;
      else
        ++n.unknown;
    }
  return n;
}

/// The log's own message in front of which flag read it, the type kept (exit 1 either way).
template <typename F>
auto naming(const std::string& flag, F&& f) {
  try {
    return f();
  } catch (const ParseError& e) {
    throw ParseError(fmt::format("map {}: {}", flag, e.what()));
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(fmt::format("map {}: {}", flag, e.what()));
  }
}

/// A bag's scans with the robot's pose at each: --pose-topic interpolated at the scan's stamp
/// (the topic checked here, so that the error names this flag, not --odom-topic), else the
/// odometry, with a warning.
MapInput read_bag_input(const MapCommand& c) {
  robot::BagOptions o = c.bag.options;
  MapInput in;
  robot::BagLaserLog b;
  if (c.pose_topic.empty()) {
    b = robot::read_bag_laser_log(c.data, o);
    in.poses = "odometry";
    fmt::print(stderr,
               "implicit map: warning: no --pose-topic: the map of {} is built from the raw "
               "odometry of {}, which drifts; give a ground-truth or localizer topic "
               "(geometry_msgs/PoseStamped) with --pose-topic\n",
               printable(c.data), o.odom_topic);
  } else {
    const robot::BagContents bag =
        robot::read_bag(c.data, {o.scan_topic, c.pose_topic, "/tf_static", "/tf"});
    const std::size_t t = bag.find_topic(c.pose_topic);
    if (t == bag.topics.size()) {
      std::string present;
      for (const robot::BagTopic& topic : bag.topics)
        present += fmt::format("{}{} ({})", present.empty() ? "" : ", ", printable(topic.name),
                               printable(topic.type, 60));
      throw ParseError(
          fmt::format("{}: expected topic '{}' (--pose-topic), got no such topic; the bag has: {}",
                      bag.source, printable(c.pose_topic), present.empty() ? "none" : present));
    }
    if (robot::bag_base_type(bag.topics[t].type) != "geometry_msgs/PoseStamped")
      throw ParseError(fmt::format(
          "{}: topic '{}' (--pose-topic): expected messages of type geometry_msgs/PoseStamped, "
          "got '{}' (odometry is read without --pose-topic, from --odom-topic)",
          bag.source, printable(c.pose_topic), printable(bag.topics[t].type, 60)));
    o.odom_topic = c.pose_topic;
    b = robot::bag_laser_log(bag, o);
    in.poses = c.pose_topic;
  }
  in.log = std::move(b.log);
  in.scans_outside_poses = b.scans_outside_odometry;
  return in;
}

void run_map(const MapCommand& c) {
  const std::string out = c.ctx.out_dir.string();
  const auto t0 = std::chrono::steady_clock::now();
  require_bag_for_flags(c.bag, c.data, "map");
  // The bag reader's errors name the file, topic and flag themselves.
  const MapInput in = robot::is_bag(c.data)
                          ? read_bag_input(c)
                          : MapInput{naming("--data", [&] { return robot::read_carmen(c.data); })};
  const robot::CarmenLog& log = in.log;
  require(!log.scans.empty(),
          "map --data {}: expected at least one scan with a pose, got none ({} outside the "
          "poses' time span)",
          printable(c.data), in.scans_outside_poses);
  // The laser's pose on the robot, constant in a log: the first scan's laser pose seen from its
  // robot pose. The mapper takes robot poses and the mount, so the mount is taken off the
  // recorded laser poses (zero for the bundled logs, whose two poses are equal).
  const robot::Pose mount = robot::between(log.odometry_poses.front(), log.laser_poses.front());
  const robot::LaserMount laser_mount{mount(0), mount(1), wrap_angle(mount(2))};
  const robot::Pose mount_pose(laser_mount.x, laser_mount.y, laser_mount.yaw);
  std::vector<robot::Pose> robot_poses(log.scans.size());
  for (std::size_t k = 0; k < log.scans.size(); ++k)
    robot_poses[k] =
        robot::compose(log.laser_poses[k], robot::between(mount_pose, robot::Pose::Zero()));
  robot::GridMappingOptions options;
  options.resolution = c.resolution;
  options.max_range = c.max_range;
  options.min_echoes = c.min_echoes;
  const robot::OccupancyGrid grid = naming("--data " + c.data, [&] {
    return robot::build_map(robot_poses, log.scans, laser_mount, options);
  });
  naming("--out", [&] {
    robot::save_map(grid, out);
    return 0;
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const CellCounts n = count_cells(grid);
  const double width_m = grid.width() * grid.resolution();
  const double height_m = grid.height() * grid.resolution();
  if (c.ctx.json) {
    print_json({{"file", out},
                {"data", c.data},
                {"scans", log.scans.size()},
                {"poses", in.poses},
                {"scans_outside_poses", in.scans_outside_poses},
                {"resolution", grid.resolution()},
                {"max_range", c.max_range},
                {"min_echoes", c.min_echoes},
                {"mount", {laser_mount.x, laser_mount.y, laser_mount.yaw}},
                {"width", grid.width()},
                {"height", grid.height()},
                {"cells", static_cast<std::int64_t>(grid.width()) * grid.height()},
                {"width_m", width_m},
                {"height_m", height_m},
                {"origin", {grid.origin().x(), grid.origin().y()}},
                {"occupied", n.occupied},
                {"free", n.free},
                {"unknown", n.unknown},
                {"seconds", seconds}});
    return;
  }
  fmt::print(
      "{}: {} x {} cells of {} m ({:.2f} m x {:.2f} m) from {} scans of {}: {} occupied, {} "
      "free, {} unknown; {:.2f} s\n",
      out, grid.width(), grid.height(), grid.resolution(), width_m, height_m, log.scans.size(),
      c.data, n.occupied, n.free, n.unknown, seconds);
  if (in.poses != "log")
    fmt::print("  poses from {}; {} scans left out (outside the poses' time span)\n",
               in.poses == "odometry" ? c.bag.options.odom_topic + " (raw odometry)" : in.poses,
               in.scans_outside_poses);
}

void setup_map(CLI::App& sub) {
  auto cmd = std::make_shared<MapCommand>();
  sub.add_option("--data", cmd->data,
                 "The CARMEN laser log (.log or .log.gz, e.g. data/carmen/aces-corrected.log.gz) "
                 "or a ROS bag (.mcap, .db3, ROS 1 .bag, or a rosbag2 folder)")
      ->required();
  add_bag_flags(sub, cmd->bag);
  // Refused without a bag like the other bag flags (it would be ignored).
  cmd->bag.given.push_back(
      sub.add_option("--pose-topic", cmd->pose_topic,
                     "ROS bag as --data: the robot's pose (geometry_msgs/PoseStamped, e.g. ground "
                     "truth or a localizer), interpolated at each scan's stamp; scans outside its "
                     "time span are left out and counted. Default: the raw odometry of "
                     "--odom-topic, with a warning (it drifts)")
          ->check(CLI::Validator(
              [](std::string& text) -> std::string {
                return text.empty() ? "expected a topic name, got an empty one" : "";
              },
              "TOPIC")));
  add_common_options(sub, cmd->ctx);
  sub.get_option("--out")
      ->description("The map's YAML FILE (.yaml or .yml); the image goes beside it as .pgm")
      ->required()
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const std::string ext = std::filesystem::path(text).extension().string();
            if (ext == ".yaml" || ext == ".yml") return {};
            return fmt::format("expected a YAML file name ending in .yaml or .yml, got '{}'",
                               printable(text));
          },
          "FILE.yaml"));
  sub.add_option("--resolution", cmd->resolution, "[m] cell size")
      ->check(in_range(0.005, 1.0))
      ->capture_default_str();
  sub.add_option("--max-range", cmd->max_range,
                 "[m] beams are used up to this range; longer readings only clear cells (0: "
                 "each scan's no-return range)")
      ->check(in_range(0.0, 1000.0))
      ->capture_default_str();
  sub.add_option("--min-echoes", cmd->min_echoes,
                 "a cell where beams of this many scans ended is occupied, whatever the beams "
                 "that crossed it (0: log-odds only; docs/cli.md)")
      ->check(in_range(0, 255))
      ->capture_default_str();
  set_examples(sub, {"implicit map --data data/carmen/aces-corrected.log.gz --out aces.yaml",
                     "implicit map --data data/carmen/intel-corrected.log.gz --out intel.yaml "
                     "--resolution 0.1 --json",
                     "implicit map --data run.mcap --pose-topic /ground_truth --out run.yaml"});
  sub.callback([cmd] { run_map(*cmd); });
}

const Registrar register_map{
    "map", "An occupancy grid map (PGM + YAML) from a CARMEN laser log or a ROS bag", setup_map};

}  // namespace
}  // namespace implicit::app
