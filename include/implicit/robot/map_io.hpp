#pragma once
// ROS map_server map files: a YAML file that names a greyscale image and says how to read it.
//
//   image: lab.pgm              # relative to the YAML file's folder (or absolute)
//   resolution: 0.05            # metres per pixel
//   origin: [-10.0, -7.5, 0.0]  # world (x, y) of the lower-left pixel's corner, and a yaw (0)
//   negate: 0                   # 1: white is occupied
//   occupied_thresh: 0.65
//   free_thresh: 0.196
//   mode: trinary               # optional: trinary (default), scale or raw
//
//   OccupancyGrid grid = load_map("maps/lab.yaml");
//   save_map(grid, "out/lab.yaml");   // writes out/lab.pgm, then out/lab.yaml
//
// Pixels convert as map_server converts them: p = (maxval - v) / maxval, or v / maxval with
// negate; trinary gives 100 above occupied_thresh, 0 below free_thresh and -1 between; scale
// gives round(99 (p - free) / (occupied - free)) between instead; raw takes v itself (0..100,
// or 255 for unknown). The image's first row is the highest y. Images are PGM, binary (P5,
// 8 or 16 bits) or plain (P2). Rotated maps (a non-zero yaw) are refused, like every other
// malformed file, with a ParseError naming the file, and the line and key where there is one.
// Full description: docs/formats.md, "Occupancy map files".

#include <filesystem>
#include <string_view>

#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::robot {

/// Reads a map: the YAML file, then the image it names.
OccupancyGrid load_map(const std::filesystem::path& yaml_file);

/// The same from memory: `yaml_text` the YAML file's content, `pgm_bytes` the image's, `name`
/// the YAML file's name in messages (the image is named after it, as load_map would find it).
OccupancyGrid parse_map(std::string_view yaml_text, std::string_view pgm_bytes,
                        std::string_view name);

/// Writes `grid` as a binary PGM beside the YAML file (same name, extension .pgm) and the YAML
/// file (trinary mode, thresholds 0.65 and 0.196, numbers that read back exactly). Occupied
/// (100) is black (0), free (0) is 254, unknown is 205, and a value c between is the grey
/// round(255 (100 - c) / 100), which loads back as occupied for c >= 65 and as free for
/// c <= 19 (OccupancyGrid::is_occupied, is_free). A grid holding only 0, 100 and -1 round-trips
/// exactly. Each file is written under a temporary name in its folder and renamed into place,
/// the image first: no half-written file ever has the final name. Throws InvalidArgument for
/// an empty grid or a failed write.
void save_map(const OccupancyGrid& grid, const std::filesystem::path& yaml_file);

}  // namespace implicit::robot
