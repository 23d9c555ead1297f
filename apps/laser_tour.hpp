#pragma once
// The path of `implicit simulate --map`: straight segments through a map's free space, kept a
// clearance away from every cell that is not free, so that a simulated robot never drives through
// a wall or into a part of the map nobody has seen. The waypoints come from --waypoints, or are
// found on the map (automatic_tour).
//
//   FreeSpace space(robot::load_map("lab.yaml"), 0.3);
//   std::vector<Vec<2>> tour = automatic_tour(space, "lab.yaml");   // closed: ends where it starts
//   if (auto stop = space.first_blocked(tour[0], tour[1])) ...        // never, for a tour

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "implicit/core/types.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::app {

/// Where a robot of radius `clearance` may stand on a map: in a free cell, at least `clearance`
/// from the centre of every cell that is not free (occupied, unknown or in between) and from the
/// map's border. Unknown cells count as walls: the simulated scans would otherwise look into
/// space the map knows nothing about.
class FreeSpace {
 public:
  /// Keeps a reference to `map`, which must outlive this object. Throws InvalidArgument for an
  /// empty map or a clearance that is negative or not finite.
  FreeSpace(const robot::OccupancyGrid& map, double clearance);

  const robot::OccupancyGrid& map() const { return map_; }
  double clearance() const { return clearance_; }

  /// [m] from p to the nearest centre of a cell that is not free, or to the border if nearer;
  /// bilinear between cell centres, capped at max(3 m, 2 clearance).
  double room(const Vec<2>& p) const;
  /// room() at the centre of cell (ix, iy), without interpolation.
  double cell_room(int ix, int iy) const;
  bool allows(const Vec<2>& p) const;
  /// The first point of the segment from a to b where the robot may not be (the segment is
  /// sampled every quarter cell, both ends included); nullopt when the whole segment is clear.
  std::optional<Vec<2>> first_blocked(const Vec<2>& a, const Vec<2>& b) const;

 private:
  double border_distance(const Vec<2>& p) const;

  const robot::OccupancyGrid& map_;
  double clearance_;
  robot::DistanceField field_;
};

/// Waypoints from text "x1,y1;x2,y2;..." (metres, blanks allowed around numbers): at least two
/// points of finite numbers. Throws InvalidArgument naming --waypoints, the point and its text.
std::vector<Vec<2>> parse_waypoints(std::string_view text);

/// A closed tour of the free space, found without help: up to 16 places, picked greedily from the
/// free cells farthest from walls and at least max(2 m, 4 clearance) apart, joined by the straight
/// segments that stay clear; the places of the largest joined group are visited depth-first along
/// a spanning tree, going straight from one place to the next wherever that segment is clear (else
/// back along the tree), and the tour returns to where it started. Deterministic: it depends on the
/// map and the clearance only. Throws InvalidArgument naming `map_name` when no two such places
/// are joined.
std::vector<Vec<2>> automatic_tour(const FreeSpace& space, const std::string& map_name);

}  // namespace implicit::app
