// Fuzz target: ROS map_server map files (src/robot/map_io.cpp), the YAML file and its image.
//
// An input is the YAML text, a line "%%", then the image's bytes (scratch.hpp's layout; the
// image may contain further "%%" lines). Properties checked on every input:
//  * parse_map accepts it or throws ParseError / InvalidArgument (anything else is a finding:
//    another exception, a crash, a sanitizer report, a hang);
//  * an accepted map holds only -1..100, and, if small, save_map then load_map gives it back
//    with the same size, resolution and origin (bit for bit) and every cell in the same class
//    (occupied, free or unknown), exactly equal where it was 0, 100 or -1.

#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "implicit/core/error.hpp"
#include "implicit/robot/map_io.hpp"
#include "scratch.hpp"

namespace {

using implicit::robot::OccupancyGrid;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "fuzz_occupancy_map: %s\n", what);
  std::abort();
}

int map_class(const OccupancyGrid& g, int ix, int iy) {
  return g.is_occupied(ix, iy) ? OccupancyGrid::kOccupied
         : g.is_free(ix, iy)   ? OccupancyGrid::kFree
                               : OccupancyGrid::kUnknown;
}

void check_round_trip(const OccupancyGrid& map) {
  const auto yaml = implicit::fuzz::scratch().path() / "round_trip.yaml";
  implicit::robot::save_map(map, yaml);
  const OccupancyGrid back = implicit::robot::load_map(yaml);
  if (back.width() != map.width() || back.height() != map.height()) fail("the size changed");
  if (back.resolution() != map.resolution()) fail("the resolution changed");
  if (back.origin() != map.origin()) fail("the origin changed");
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix) {
      const int v = map.at(ix, iy);
      const bool trinary = v == 0 || v == 100 || v == -1;
      if (trinary ? back.at(ix, iy) != v : back.at(ix, iy) != map_class(map, ix, iy))
        fail("a cell changed in the round trip");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto files = implicit::fuzz::split_files(implicit::fuzz::as_text(data, size), 2);
  OccupancyGrid map;
  try {
    map = implicit::robot::parse_map(files[0], files[1], "input.yaml");
  } catch (const implicit::ParseError&) {
    return 0;
  } catch (const implicit::InvalidArgument&) {
    return 0;
  }
  for (const std::int8_t v : map.data())
    if (v < -1 || v > 100) fail("a cell outside -1..100");
  if (map.data().size() <= 4096) check_round_trip(map);
  return 0;
}
