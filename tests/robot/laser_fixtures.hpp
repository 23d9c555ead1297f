#pragma once
// Small synthetic maps for the laser tests: a rectangular room with an inner wall and a box, and
// a map with one wall. Built cell by cell, so every distance in it can be computed by hand.

#include <cstdint>

#include "implicit/robot/occupancy_grid.hpp"

namespace implicit::testing {

/// A width_m x height_m room (walls one cell thick on the border, free inside), origin (0, 0),
/// with a short inner wall and a box so that no pose along a corridor looks like another.
inline robot::OccupancyGrid laser_room(double width_m = 8.0, double height_m = 6.0,
                                       double resolution = 0.05) {
  const int w = static_cast<int>(width_m / resolution + 0.5);
  const int h = static_cast<int>(height_m / resolution + 0.5);
  robot::OccupancyGrid g(w, h, resolution, Vec<2>::Zero(), robot::OccupancyGrid::kFree);
  auto occupy = [&](double x0, double y0, double x1, double y1) {
    for (int iy = 0; iy < h; ++iy)
      for (int ix = 0; ix < w; ++ix) {
        const Vec<2> c = g.cell_center(ix, iy);
        if (c(0) >= x0 && c(0) <= x1 && c(1) >= y0 && c(1) <= y1)
          g.at(ix, iy) = robot::OccupancyGrid::kOccupied;
      }
  };
  occupy(0, 0, width_m, resolution);                         // south wall
  occupy(0, height_m - resolution, width_m, height_m);       // north wall
  occupy(0, 0, resolution, height_m);                        // west wall
  occupy(width_m - resolution, 0, width_m, height_m);        // east wall
  occupy(0.4 * width_m, 0, 0.4 * width_m + resolution, 0.45 * height_m);  // inner wall
  occupy(0.7 * width_m, 0.6 * height_m, 0.8 * width_m, 0.75 * height_m);  // box
  return g;
}

/// A free grid with one vertical wall: the column of cells whose centre is at x = wall_x.
inline robot::OccupancyGrid one_wall_map(int width, int height, double resolution, int wall_column) {
  robot::OccupancyGrid g(width, height, resolution, Vec<2>::Zero(), robot::OccupancyGrid::kFree);
  for (int iy = 0; iy < height; ++iy) g.at(wall_column, iy) = robot::OccupancyGrid::kOccupied;
  return g;
}

}  // namespace implicit::testing
