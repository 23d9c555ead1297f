// `implicit convert`: a ROS bag (robot/bag.hpp) as the project's CARMEN log, which `implicit mcl
// --sensor laser --data FILE` and `implicit map --data FILE` read; the same log as the bag gives
// them directly, bit for bit.
#include <filesystem>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "bag_flags.hpp"
#include "context.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/bag.hpp"
#include "implicit/robot/csv_table.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct ConvertCommand {
  std::string data;
  RunContext ctx;  ///< --json, and --out: here the CARMEN log FILE (--seed, --threads: unused)
  BagFlags bag;
};

void run_convert(const ConvertCommand& c) {
  const robot::BagLaserLog b = robot::read_bag_laser_log(c.data, c.bag.options);
  const std::string out = c.ctx.out_dir.string();
  robot::write_text_file(out, robot::carmen_log_text(b.log));
  const robot::LaserMount& m = b.mount;
  if (c.ctx.json) {
    print_json({{"file", out},
                {"data", c.data},
                {"scans", b.log.scans.size()},
                {"scans_outside_odometry", b.scans_outside_odometry},
                {"odometry", b.log.odometry.size()},
                {"scan_topic", c.bag.options.scan_topic},
                {"odom_topic", c.bag.options.odom_topic},
                {"base_frame", b.base_frame},
                {"laser_frame", b.laser_frame},
                {"mount", {m.x, m.y, m.yaw}},
                {"mount_from_tf", b.mount_from_tf}});
    return;
  }
  fmt::print(
      "{}: {} scans of {} ({} left out: no odometry around their stamp), {} odometry poses "
      "of {}\n  the laser ({}) on the robot ({}) at x {} m, y {} m, yaw {} rad ({})\n",
      out, b.log.scans.size(), c.bag.options.scan_topic, b.scans_outside_odometry,
      b.log.odometry.size(), c.bag.options.odom_topic, b.laser_frame, b.base_frame, m.x, m.y, m.yaw,
      b.mount_from_tf ? "from TF" : "no transform between them in the bag: zero");
}

void setup_convert(CLI::App& sub) {
  auto cmd = std::make_shared<ConvertCommand>();
  sub.add_option("--data", cmd->data,
                 "The ROS bag: an .mcap, .db3 or ROS 1 .bag file, or a rosbag2 folder with "
                 "metadata.yaml")
      ->required();
  add_common_options(sub, cmd->ctx);
  sub.get_option("--out")
      ->description("The CARMEN log FILE to write (gzip-compressed if it ends in .gz)")
      ->required();
  add_bag_flags(sub, cmd->bag);
  set_examples(sub, {"implicit convert --data run.mcap --out run.log",
                     "implicit convert --data rosbag2_folder --scan-topic /base_scan --odom-topic "
                     "/odom --out run.log.gz --json"});
  sub.callback([cmd] {
    require(robot::is_bag(cmd->data),
            "convert --data: expected a ROS bag (an .mcap, .db3 or .bag file, or a rosbag2 folder "
            "with metadata.yaml), got '{}'{}",
            printable(cmd->data), std::filesystem::exists(cmd->data) ? "" : " (no such file)");
    run_convert(*cmd);
  });
}

const Registrar register_convert{"convert", "The project's CARMEN log from a ROS bag",
                                 setup_convert};

}  // namespace
}  // namespace implicit::app
