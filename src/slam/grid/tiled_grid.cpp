#include "implicit/slam/grid/tiled_grid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <utility>
#include <vector>

#include "../../robot/log_odds_beam.hpp"
#include "implicit/core/error.hpp"
#include "implicit/robot/scan_simulation.hpp"  // sensor_pose

namespace implicit::slam {
namespace {

using robot::GridMappingOptions;

// Index of cell (lx, ly) inside its tile, and the seen bit's word and mask.
constexpr int tiled_grid_local(int ix, int iy) {
  constexpr int mask = TiledLogOddsGrid::kTileSize - 1;
  return ((iy & mask) << TiledLogOddsGrid::kTileShift) | (ix & mask);
}

bool tiled_grid_seen(const TiledLogOddsGrid::Tile& t, int k) {
  return (t.seen[static_cast<std::size_t>(k >> 6)] >> (k & 63)) & 1u;
}

// Tiles come and go in bursts: a resampling frees the tiles of the particles that die, and the
// next scan's copies on write allocate as many again. Through malloc alone, glibc hands the freed
// top of its heap back to the system and takes it again a page fault per 4 KiB: 2.1 ms against
// 0.21 ms per particle and scan (bench_grid_slam CopyOnWrite/30, docs/performance.md). Freed
// tile blocks (tile and count, one size) are kept for reuse instead, per thread (no lock), up to
// kTileCacheBlocks (about 70 MB) a thread. Under AddressSanitizer every block goes back to the
// heap, so that a use after free is still caught.
constexpr std::size_t kTileCacheBlocks = 16384;
#if defined(__SANITIZE_ADDRESS__)
#define IMPLICIT_TILE_CACHE 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IMPLICIT_TILE_CACHE 0
#endif
#endif
#ifndef IMPLICIT_TILE_CACHE
#define IMPLICIT_TILE_CACHE 1
#endif

class TileBlockCache {
 public:
  TileBlockCache() { free_.reserve(kTileCacheBlocks); }  // give() then never allocates
  ~TileBlockCache();
  void* take(std::size_t bytes) {
    if (bytes != block_ || free_.empty()) return ::operator new(bytes);
    void* p = free_.back();
    free_.pop_back();
    return p;
  }
  void give(void* p, std::size_t bytes) {
    if (block_ == 0) block_ = bytes;
    if (bytes == block_ && free_.size() < kTileCacheBlocks)
      free_.push_back(p);
    else
      ::operator delete(p);
  }

 private:
  std::size_t block_ = 0;
  std::vector<void*> free_;
};

// A grid destroyed after its thread's cache (a static one, at exit) frees to the heap: the flag
// is trivially destructible, so it can still be read then.
thread_local bool tile_cache_gone = false;
thread_local TileBlockCache tile_cache;

TileBlockCache::~TileBlockCache() {
  for (void* p : free_) ::operator delete(p);
  tile_cache_gone = true;
}

template <class T>
struct TileAllocator {
  static_assert(alignof(T) <= __STDCPP_DEFAULT_NEW_ALIGNMENT__);
  using value_type = T;
  TileAllocator() = default;
  template <class U>
  TileAllocator(const TileAllocator<U>&) {}  // NOLINT: converting, as std::allocator's
  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    const bool cached = IMPLICIT_TILE_CACHE && !tile_cache_gone;
    return static_cast<T*>(cached ? tile_cache.take(bytes) : ::operator new(bytes));
  }
  void deallocate(T* p, std::size_t n) {
    if (!IMPLICIT_TILE_CACHE || tile_cache_gone)
      ::operator delete(p);
    else
      tile_cache.give(p, n * sizeof(T));
  }
  friend bool operator==(const TileAllocator&, const TileAllocator&) { return true; }
};

}  // namespace

TiledLogOddsGrid::TiledLogOddsGrid(const GridMappingOptions& options) : options_(options) {
  options.validate();
}

Eigen::Vector2i TiledLogOddsGrid::world_to_cell(const Vec<2>& p) const {
  const Vec<2> g = p * (1.0 / options_.resolution);
  require(g.allFinite() && g.cwiseAbs().maxCoeff() < kMaxCell,
          "TiledLogOddsGrid::world_to_cell: expected a finite point within {} cells of the origin "
          "({} m at {} m), got ({}, {})",
          kMaxCell, kMaxCell * options_.resolution, options_.resolution, p.x(), p.y());
  return Eigen::Vector2i(static_cast<int>(std::floor(g.x())), static_cast<int>(std::floor(g.y())));
}

std::ptrdiff_t TiledLogOddsGrid::slot_of_tile(int tx, int ty) const {
  const int rx = tx - tile_x0_, ry = ty - tile_y0_;
  if (rx < 0 || ry < 0 || rx >= tiles_w_ || ry >= tiles_h_) return -1;
  return std::ptrdiff_t{ry} * tiles_w_ + rx;
}

const TiledLogOddsGrid::Tile* TiledLogOddsGrid::tile_at(int ix, int iy) const {
  // >> on a negative int floors (C++20), as the tile of cell -1 must be tile -1.
  const std::ptrdiff_t slot = slot_of_tile(ix >> kTileShift, iy >> kTileShift);
  return slot < 0 ? nullptr : tiles_[static_cast<std::size_t>(slot)].get();
}

float TiledLogOddsGrid::log_odds(int ix, int iy) const {
  const Tile* t = tile_at(ix, iy);
  return t ? t->log_odds[static_cast<std::size_t>(tiled_grid_local(ix, iy))] : 0.0f;
}

double TiledLogOddsGrid::probability(int ix, int iy) const {
  return 1.0 - 1.0 / (1.0 + std::exp(double(log_odds(ix, iy))));
}

bool TiledLogOddsGrid::observed(int ix, int iy) const {
  const Tile* t = tile_at(ix, iy);
  return t && tiled_grid_seen(*t, tiled_grid_local(ix, iy));
}

int TiledLogOddsGrid::echoes(int ix, int iy) const {
  const Tile* t = tile_at(ix, iy);
  return t ? t->echoes[static_cast<std::size_t>(tiled_grid_local(ix, iy))] : 0;
}

bool TiledLogOddsGrid::echoed(int ix, int iy) const {
  return robot::detail::echoed(echoes(ix, iy), options_);
}

double TiledLogOddsGrid::occupancy_evidence(int ix, int iy) const {
  const Tile* t = tile_at(ix, iy);
  if (!t) return 0.0;
  const auto k = static_cast<std::size_t>(tiled_grid_local(ix, iy));
  if (robot::detail::echoed(t->echoes[k], options_))
    return 1.0;  // one lookup: the scan match's loop
  const float l = t->log_odds[k];
  return l > 0.0f ? std::tanh(0.5 * static_cast<double>(l)) : 0.0;
}

void TiledLogOddsGrid::cover(int tx0, int ty0, int tx1, int ty1) {
  if (!tiles_.empty() && slot_of_tile(tx0, ty0) >= 0 && slot_of_tile(tx1, ty1) >= 0) return;
  int nx0 = tx0, ny0 = ty0, nx1 = tx1, ny1 = ty1;
  if (!tiles_.empty()) {
    nx0 = std::min(nx0, tile_x0_);
    ny0 = std::min(ny0, tile_y0_);
    nx1 = std::max(nx1, tile_x0_ + tiles_w_ - 1);
    ny1 = std::max(ny1, tile_y0_ + tiles_h_ - 1);
  }
  const auto slots = [](int x0, int y0, int x1, int y1) {
    return static_cast<double>(x1 - x0 + 1) * static_cast<double>(y1 - y0 + 1);
  };
  require(slots(nx0, ny0, nx1, ny1) <= static_cast<double>(kMaxTileSlots),
          "TiledLogOddsGrid::integrate: expected a map of at most {} tiles of {} x {} cells, got "
          "{} x {} tiles: x spans {} .. {} m and y spans {} .. {} m. Limit max_range or coarsen "
          "the resolution",
          kMaxTileSlots, kTileSize, kTileSize, nx1 - nx0 + 1, ny1 - ny0 + 1,
          nx0 * kTileSize * options_.resolution, (nx1 + 1) * kTileSize * options_.resolution,
          ny0 * kTileSize * options_.resolution, (ny1 + 1) * kTileSize * options_.resolution);
  // Room to grow by a quarter on each side that grows, so that a robot exploring re-lays the
  // index a logarithmic number of times, not once per scan (within the limit).
  if (!tiles_.empty()) {
    const int gx = std::max(2, tiles_w_ / 4), gy = std::max(2, tiles_h_ / 4);
    const int px0 = nx0 < tile_x0_ ? nx0 - gx : nx0, py0 = ny0 < tile_y0_ ? ny0 - gy : ny0;
    const int px1 = nx1 > tile_x0_ + tiles_w_ - 1 ? nx1 + gx : nx1;
    const int py1 = ny1 > tile_y0_ + tiles_h_ - 1 ? ny1 + gy : ny1;
    if (slots(px0, py0, px1, py1) <= static_cast<double>(kMaxTileSlots)) {
      nx0 = px0, ny0 = py0, nx1 = px1, ny1 = py1;
    }
  }
  const int w = nx1 - nx0 + 1, h = ny1 - ny0 + 1;
  std::vector<TilePtr> grown(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int ry = 0; ry < tiles_h_; ++ry)
    for (int rx = 0; rx < tiles_w_; ++rx)
      grown[static_cast<std::size_t>(ry + tile_y0_ - ny0) * static_cast<std::size_t>(w) +
            static_cast<std::size_t>(rx + tile_x0_ - nx0)] =
          std::move(tiles_[static_cast<std::size_t>(ry) * static_cast<std::size_t>(tiles_w_) +
                           static_cast<std::size_t>(rx)]);
  tiles_ = std::move(grown);
  tile_x0_ = nx0, tile_y0_ = ny0, tiles_w_ = w, tiles_h_ = h;
}

TiledLogOddsGrid::Tile& TiledLogOddsGrid::writable(std::size_t slot) {
  TilePtr& p = tiles_[slot];
  std::shared_ptr<Tile> own;
  if (!p) {
    own = std::allocate_shared<Tile>(TileAllocator<Tile>());
  } else if (p.use_count() > 1) {
    // Copy on write: the other grids keep the old tile.
    own = std::allocate_shared<Tile>(TileAllocator<Tile>(), *p);
  } else {
    // This grid holds the only pointer, so no other grid can read the tile any more. The last
    // other holder released it (an acq_rel decrement) after its last read; the fence orders those
    // reads before the writes that follow, when that holder ran on another thread.
    std::atomic_thread_fence(std::memory_order_acquire);
    // The tile was made non-const (allocate_shared<Tile> above); only the pointer's type is const.
    return const_cast<Tile&>(*p);
  }
  Tile& t = *own;
  p = std::move(own);
  return t;
}

void TiledLogOddsGrid::integrate(const robot::Pose& robot_pose, const robot::LaserMount& mount,
                                 const robot::LaserScan& scan) {
  robot::detail::check_scan_input(robot_pose, mount, scan, "TiledLogOddsGrid::integrate");
  const robot::Pose s = robot::sensor_pose(robot_pose, mount);
  const double inv_res = 1.0 / options_.resolution;
  // Grid units, origin (0, 0): the same arithmetic as LogOddsGrid with its origin at (0, 0).
  const Vec<2> g = s.head<2>() * inv_res;

  // Every beam stays within its longest length of the sensor: cover that square (plus two cells
  // for rounding at the ends) before the first write, so that a refusal changes nothing.
  double longest = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const robot::detail::BeamUse use = robot::detail::beam_use(scan, i, options_.max_range);
    if (use.used) longest = std::max(longest, use.length);
  }
  const double reach = longest * inv_res + 2.0;
  const Vec<2> lo = g.array() - reach, hi = g.array() + reach;
  require(std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()) < kMaxCell,
          "TiledLogOddsGrid::integrate: expected beams within {} m of the origin, got a sensor at "
          "({}, {}) with beams of up to {} m",
          kMaxCell * options_.resolution, s(0), s(1), longest);
  cover(static_cast<int>(std::floor(lo.x())) >> kTileShift,
        static_cast<int>(std::floor(lo.y())) >> kTileShift,
        static_cast<int>(std::floor(hi.x())) >> kTileShift,
        static_cast<int>(std::floor(hi.y())) >> kTileShift);

  // Cells relative to the index's corner; the tile being written is kept between cells (a beam
  // crosses 32 cells of a tile in a row at best, and most cells of a beam share its tile).
  const int cx0 = tile_x0_ * kTileSize, cy0 = tile_y0_ * kTileSize;
  const int cw = tiles_w_ * kTileSize, ch = tiles_h_ * kTileSize;
  std::size_t cached_slot = std::numeric_limits<std::size_t>::max();
  Tile* cached = nullptr;
  const double clamp = options_.clamp;
  const auto inside = [&](int ix, int iy) {
    return ix - cx0 >= 0 && iy - cy0 >= 0 && ix - cx0 < cw && iy - cy0 < ch;
  };
  // The end cells of this scan's hits (relative to the index's corner), so that a scan counts
  // once per cell: per thread, as the freed tiles are, so that no grid allocates for it.
  thread_local std::vector<std::pair<int, int>> scan_ends;
  scan_ends.clear();
  const auto update = [&](int ix, int iy, double delta) {
    const int rx = ix - cx0, ry = iy - cy0;
    const std::size_t slot =
        static_cast<std::size_t>(ry >> kTileShift) * static_cast<std::size_t>(tiles_w_) +
        static_cast<std::size_t>(rx >> kTileShift);
    if (slot != cached_slot) {
      cached = &writable(slot);
      cached_slot = slot;
    }
    const int k = tiled_grid_local(rx, ry);
    float& v = cached->log_odds[static_cast<std::size_t>(k)];
    v = robot::detail::add_log_odds(v, delta, clamp);
    if (delta > 0.0) scan_ends.emplace_back(rx, ry);  // only a hit adds
    cached->seen[static_cast<std::size_t>(k >> 6)] |= std::uint64_t{1} << (k & 63);
  };
  const int sx = static_cast<int>(std::floor(g.x())), sy = static_cast<int>(std::floor(g.y()));
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const robot::detail::BeamUse use = robot::detail::beam_use(scan, i, options_.max_range);
    if (!use.used) continue;
    const double angle = s(2) + scan.bearing(i);
    const Vec<2> d(std::cos(angle), std::sin(angle));
    robot::detail::trace_beam(g, d, sx, sy, use.length * inv_res, use.hit, options_, inside,
                              update);
  }
  // The tiles of the end cells are this grid's own by now (written above).
  robot::detail::count_scan_echoes(scan_ends, [&](const std::pair<int, int>& c) -> std::uint8_t& {
    const auto [rx, ry] = c;
    const std::size_t slot =
        static_cast<std::size_t>(ry >> kTileShift) * static_cast<std::size_t>(tiles_w_) +
        static_cast<std::size_t>(rx >> kTileShift);
    return writable(slot).echoes[static_cast<std::size_t>(tiled_grid_local(rx, ry))];
  });
}

robot::OccupancyGrid TiledLogOddsGrid::to_occupancy_grid() const {
  // The bounding box of the observed cells.
  int x0 = std::numeric_limits<int>::max(), y0 = x0;
  int x1 = std::numeric_limits<int>::min(), y1 = x1;
  for (int ty = 0; ty < tiles_h_; ++ty)
    for (int tx = 0; tx < tiles_w_; ++tx) {
      const Tile* t = tiles_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_w_) +
                             static_cast<std::size_t>(tx)]
                          .get();
      if (!t) continue;
      for (int k = 0; k < kTileCells; ++k) {
        if (!tiled_grid_seen(*t, k)) continue;
        const int ix = (tile_x0_ + tx) * kTileSize + (k & (kTileSize - 1));
        const int iy = (tile_y0_ + ty) * kTileSize + (k >> kTileShift);
        x0 = std::min(x0, ix), y0 = std::min(y0, iy);
        x1 = std::max(x1, ix), y1 = std::max(y1, iy);
      }
    }
  if (x1 < x0) return {};
  const double r = options_.resolution;
  // At most kMaxTileSlots tiles of kTileCells cells: 2^30 cells, within OccupancyGrid's limit.
  robot::OccupancyGrid out(x1 - x0 + 1, y1 - y0 + 1, r, Vec<2>(x0 * r, y0 * r),
                           robot::OccupancyGrid::kUnknown);
  for (int iy = y0; iy <= y1; ++iy)
    for (int ix = x0; ix <= x1; ++ix)
      if (observed(ix, iy))
        out.at(ix - x0, iy - y0) =
            echoed(ix, iy) ? std::int8_t{100} : robot::detail::occupancy_value(log_odds(ix, iy));
  return out;
}

std::size_t TiledLogOddsGrid::tile_count() const {
  return static_cast<std::size_t>(
      std::count_if(tiles_.begin(), tiles_.end(), [](const TilePtr& p) { return p != nullptr; }));
}

std::size_t TiledLogOddsGrid::unique_tile_count() const {
  return static_cast<std::size_t>(std::count_if(
      tiles_.begin(), tiles_.end(), [](const TilePtr& p) { return p && p.use_count() == 1; }));
}

TiledGridBytes TiledLogOddsGrid::bytes() const {
  TiledGridBytes b;
  b.tiles = tile_count();
  b.unique_tiles = unique_tile_count();
  b.index = sizeof(*this) + tiles_.capacity() * sizeof(TilePtr);
  b.owned = b.index + b.unique_tiles * sizeof(Tile);
  b.shared = (b.tiles - b.unique_tiles) * sizeof(Tile);
  return b;
}

std::size_t TiledLogOddsGrid::distinct_tiles(std::span<const TiledLogOddsGrid> grids) {
  std::unordered_set<const Tile*> seen;
  for (const TiledLogOddsGrid& g : grids)
    for (const TilePtr& p : g.tiles_)
      if (p) seen.insert(p.get());
  return seen.size();
}

}  // namespace implicit::slam
