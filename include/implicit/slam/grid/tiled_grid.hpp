#pragma once
// The occupancy grid each particle of grid SLAM carries: log-odds and echoes (robot/
// grid_mapping.hpp's inverse sensor model, cell by cell the same as LogOddsGrid), unbounded, in
// square tiles of 32 x 32 cells shared between grids until one of them writes.
//
// A Rao-Blackwellized particle filter copies maps at every resampling: M particles, each with a
// map of the whole area seen so far. A dense copy would cost the whole map per particle; here a
// copy copies the tile index (one pointer per tile) and each tile is shared, read-only, by every
// grid that holds it. A write to a shared tile first copies that tile (copy on write), so a
// particle pays only for the tiles its own scans touch after a resampling.
//
//   slam::TiledLogOddsGrid map({.resolution = 0.05, .max_range = 40.0});
//   map.integrate(robot_pose, mount, scan);           // creates tiles where the beams go
//   slam::TiledLogOddsGrid child = map;               // resampling: shares every tile
//   child.integrate(next_pose, mount, next_scan);     // copies the tiles this scan touches
//   robot::OccupancyGrid dense = child.to_occupancy_grid();   // map_io's save_map writes it
//
// Cell (ix, iy) covers [ix r, (ix + 1) r) x [iy r, (iy + 1) r) in the world (r the resolution):
// the origin is fixed at (0, 0), so the cells of all grids of one resolution line up (a dense map
// from to_occupancy_grid has its corner on a multiple of r, as robot::build_map's). A cell never
// observed has log-odds 0 (p = 1/2), whether its tile exists or not.
//
// Threads: different grids may be read and written on different threads at once, even when they
// share tiles (a shared tile is never written; a write first makes its tile this grid's own). One
// grid is not to be written while another thread uses it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/types.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/occupancy_grid.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::slam {

/// What a grid holds, for the memory per particle: the index is always the grid's own; a tile
/// held by no other grid is freed with it, a shared one is not.
struct TiledGridBytes {
  std::size_t tiles = 0;         ///< tiles the grid holds (created by a write)
  std::size_t unique_tiles = 0;  ///< of them, those no other grid holds
  std::size_t index = 0;         ///< [bytes] the grid object and its tile index
  std::size_t owned = 0;         ///< [bytes] index + unique tiles: what this grid alone costs
  std::size_t shared = 0;        ///< [bytes] the tiles it shares with other grids
};

class TiledLogOddsGrid {
 public:
  static constexpr int kTileSize = 32;  ///< cells per tile side (a power of two)
  static constexpr int kTileShift = 5;  ///< log2(kTileSize)
  static constexpr int kTileCells = kTileSize * kTileSize;
  /// Cell indices stay within +-kMaxCell (2^29): 26 800 km at 0.05 m, and no int overflow.
  static constexpr int kMaxCell = 1 << 29;
  /// At most this many tile slots (2^20): 16 MiB of index and 2^30 cells (1.6 km square at 0.05 m).
  static constexpr std::size_t kMaxTileSlots = std::size_t{1} << 20;

  struct Tile {
    std::array<float, kTileCells> log_odds{};           ///< row-major, row 0 the lowest y
    std::array<std::uint64_t, kTileCells / 64> seen{};  ///< bit k: cell k was observed
    std::array<std::uint8_t, kTileCells> echoes{};      ///< scans with a beam ending in the cell
  };

  /// Uses options.resolution as the cell size and the rest as the inverse sensor model
  /// (options.margin is not used: the grid grows as needed). Throws InvalidArgument for invalid
  /// options (GridMappingOptions::validate names the field).
  explicit TiledLogOddsGrid(const robot::GridMappingOptions& options = {});

  double resolution() const { return options_.resolution; }
  const robot::GridMappingOptions& options() const { return options_; }

  /// The cell that holds world point p (floor of p / resolution). Throws InvalidArgument for a
  /// non-finite point or one beyond kMaxCell cells from the origin.
  Eigen::Vector2i world_to_cell(const Vec<2>& p) const;
  /// The world coordinates of the centre of cell (ix, iy).
  Vec<2> cell_center(int ix, int iy) const {
    return Vec<2>((ix + 0.5) * options_.resolution, (iy + 0.5) * options_.resolution);
  }

  /// Any cell's log-odds: 0 for a cell never observed (in a tile or not).
  float log_odds(int ix, int iy) const;
  /// 1 - 1 / (1 + exp(log-odds)): 1/2 for a cell never observed.
  double probability(int ix, int iy) const;
  bool observed(int ix, int iy) const;
  /// The scans (up to 255) with a beam that ended in the cell.
  int echoes(int ix, int iy) const;
  /// At least options().min_echoes (> 0) of them: occupied whatever the log-odds.
  bool echoed(int ix, int iy) const;
  /// The cell's occupancy evidence: 1 where beams of at least options().min_echoes (> 0) scans
  /// ended, else max(0, 2p - 1) = max(0, tanh(log-odds / 2)).
  double occupancy_evidence(int ix, int iy) const;
  /// The same for a cell given as world_to_cell returns it.
  float log_odds(const Eigen::Vector2i& cell) const { return log_odds(cell.x(), cell.y()); }
  double probability(const Eigen::Vector2i& cell) const { return probability(cell.x(), cell.y()); }
  bool observed(const Eigen::Vector2i& cell) const { return observed(cell.x(), cell.y()); }

  /// Adds one scan taken at robot_pose (LogOddsGrid::integrate's model, with no edge: tiles
  /// are created where the beams go). All or nothing: throws InvalidArgument, before any cell
  /// changes, for a scan that fails LaserScan::validate, a non-finite pose or mount, or beams
  /// that would take the grid beyond kMaxCell or kMaxTileSlots (naming the extent).
  void integrate(const robot::Pose& robot_pose, const robot::LaserMount& mount,
                 const robot::LaserScan& scan);

  /// The cells observed so far, as a dense grid over their bounding box (its corner at a cell
  /// corner, cell values as LogOddsGrid::to_occupancy: round(100 p), -1 never observed). An
  /// empty OccupancyGrid (empty() true) when no cell is observed yet.
  robot::OccupancyGrid to_occupancy_grid() const;

  std::size_t tile_count() const;
  /// Tiles no other grid shares (use_count 1): the tiles this grid has written since it was
  /// copied, and those no copy of it holds any more.
  std::size_t unique_tile_count() const;
  TiledGridBytes bytes() const;
  /// The tiles `grids` (a particle set's maps) hold together, each shared tile counted once:
  /// times sizeof(Tile), plus each grid's bytes().index, the memory of the whole set.
  static std::size_t distinct_tiles(std::span<const TiledLogOddsGrid> grids);

 private:
  using TilePtr = std::shared_ptr<const Tile>;
  // The slot of tile (tx, ty) in tiles_, or -1 when it lies outside the index.
  std::ptrdiff_t slot_of_tile(int tx, int ty) const;
  const Tile* tile_at(int ix, int iy) const;
  // Makes the index cover tiles [tx0, tx1] x [ty0, ty1] (throws past kMaxTileSlots).
  void cover(int tx0, int ty0, int tx1, int ty1);
  // Tile `slot` for writing: created when absent, copied first when another grid shares it.
  Tile& writable(std::size_t slot);

  robot::GridMappingOptions options_;
  // A dense 2-D array of tile pointers over the tiles' bounding box (row-major), not a hash map:
  // resampling copies every particle's index, and copying an array of pointers is one
  // allocation plus a count increment per tile, where a hash map allocates a node per tile and
  // rehashes; a lookup is two shifts and an add, in the loop over every cell a beam crosses. The
  // cost is a null slot (16 bytes) for every tile of the box no beam reached, e.g. the middle
  // of a loop around a block: small next to the tiles themselves (4 KiB each).
  std::vector<TilePtr> tiles_;
  int tile_x0_ = 0, tile_y0_ = 0;  // tile coordinates of slot 0
  int tiles_w_ = 0, tiles_h_ = 0;
};

}  // namespace implicit::slam
