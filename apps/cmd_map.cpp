// `implicit map`: the occupancy grid of a CARMEN laser log, built from the log's recorded poses
// and scans (log-odds mapping with known poses, grid_mapping.hpp) and written as a map_server map
// (PGM and YAML), the map `implicit mcl --sensor laser --map` and `implicit simulate --map` read.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "context.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/weights.hpp"
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

void run_map(const MapCommand& c) {
  const std::string out = c.ctx.out_dir.string();
  const auto t0 = std::chrono::steady_clock::now();
  const robot::CarmenLog log = naming("--data", [&] { return robot::read_carmen(c.data); });
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
                {"resolution", grid.resolution()},
                {"max_range", c.max_range},
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
}

void setup_map(CLI::App& sub) {
  auto cmd = std::make_shared<MapCommand>();
  sub.add_option("--data", cmd->data,
                 "The CARMEN laser log (.log or .log.gz, e.g. data/carmen/aces-corrected.log.gz)")
      ->required();
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
  set_examples(sub, {"implicit map --data data/carmen/aces-corrected.log.gz --out aces.yaml",
                     "implicit map --data data/carmen/intel-corrected.log.gz --out intel.yaml "
                     "--resolution 0.1 --json"});
  sub.callback([cmd] { run_map(*cmd); });
}

const Registrar register_map{"map", "An occupancy grid map (PGM + YAML) from a CARMEN laser log",
                             setup_map};

}  // namespace
}  // namespace implicit::app
