// Paths through a map's free space for `implicit simulate --map` (laser_tour.hpp).
#include "laser_tour.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <system_error>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::app {
namespace {

// The automatic tour: enough places to cover a building's main rooms and corridors without
// making the visibility graph (all pairs of places) costly; and far enough apart that the robot
// drives a few metres between scans of different places.
constexpr std::size_t kMaxPlaces = 16;
constexpr double kMinSpacing = 2.0;  // [m]

/// Every cell that is not free, as an occupied cell: the walls of the free space.
robot::OccupancyGrid walls_of(const robot::OccupancyGrid& map) {
  require(!map.empty(), "free space: expected a map with cells, got an empty one");
  robot::OccupancyGrid walls(map.width(), map.height(), map.resolution(), map.origin(),
                             robot::OccupancyGrid::kFree);
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix)
      if (!map.is_free(ix, iy)) walls.at(ix, iy) = robot::OccupancyGrid::kOccupied;
  return walls;
}

double checked_clearance(double clearance) {
  require(std::isfinite(clearance) && clearance >= 0,
          "free space: expected a clearance >= 0 [m], got {}", clearance);
  return clearance;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool parse_number(std::string_view s, double& v) {
  s = trimmed(s);
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && error == std::errc() && end == s.data() + s.size() && std::isfinite(v);
}

/// The spanning tree of one group of joined places, grown depth-first from `root` (nearest
/// neighbour first), with what the tour needs: parents, depths and the visiting order.
struct Tree {
  std::vector<int> parent, depth, order;
};

void grow(const std::vector<Vec<2>>& places, const std::vector<std::vector<bool>>& joined, int v,
          Tree& t) {
  t.order.push_back(v);
  std::vector<int> next;
  for (std::size_t u = 0; u < places.size(); ++u)
    if (joined[static_cast<std::size_t>(v)][u]) next.push_back(static_cast<int>(u));
  const Vec<2>& from = places[static_cast<std::size_t>(v)];
  std::stable_sort(next.begin(), next.end(), [&](int a, int b) {
    return (places[static_cast<std::size_t>(a)] - from).norm() <
           (places[static_cast<std::size_t>(b)] - from).norm();
  });
  for (int u : next) {
    const auto k = static_cast<std::size_t>(u);
    if (t.depth[k] >= 0) continue;
    t.parent[k] = v;
    t.depth[k] = t.depth[static_cast<std::size_t>(v)] + 1;
    grow(places, joined, u, t);
  }
}

/// The places after u on the tree's path from u to w, w last.
std::vector<int> tree_path(const Tree& t, int u, int w) {
  std::vector<int> up, down;
  int a = u, b = w;
  while (a != b) {
    if (t.depth[static_cast<std::size_t>(a)] >= t.depth[static_cast<std::size_t>(b)]) {
      a = t.parent[static_cast<std::size_t>(a)];
      up.push_back(a);
    } else {
      down.push_back(b);
      b = t.parent[static_cast<std::size_t>(b)];
    }
  }
  up.insert(up.end(), down.rbegin(), down.rend());
  return up;
}

/// Places to visit: the free cells with the most room first, each at least `spacing` from those
/// already taken.
std::vector<Vec<2>> pick_places(const FreeSpace& space, double spacing) {
  const robot::OccupancyGrid& map = space.map();
  struct Candidate {
    double room;
    int ix, iy;
  };
  std::vector<Candidate> candidates;
  for (int iy = 0; iy < map.height(); ++iy)
    for (int ix = 0; ix < map.width(); ++ix)
      if (map.is_free(ix, iy) && space.allows(map.cell_center(ix, iy)))
        candidates.push_back({space.cell_room(ix, iy), ix, iy});
  // Stable: among cells with equal room (beyond the cap, say) the first in the map comes first.
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.room > b.room; });
  std::vector<Vec<2>> places;
  for (const Candidate& c : candidates) {
    const Vec<2> p = map.cell_center(c.ix, c.iy);
    const bool apart = std::all_of(places.begin(), places.end(),
                                   [&](const Vec<2>& q) { return (p - q).norm() >= spacing; });
    if (apart) places.push_back(p);
    if (places.size() == kMaxPlaces) break;
  }
  return places;
}

/// The largest group of places joined to each other (the first found on a tie: the one with the
/// most open place), as a membership mask.
std::vector<bool> largest_group(const std::vector<std::vector<bool>>& joined) {
  const std::size_t n = joined.size();
  std::vector<int> group(n, -1);
  std::vector<std::size_t> sizes;
  for (std::size_t s = 0; s < n; ++s) {
    if (group[s] >= 0) continue;
    const int g = static_cast<int>(sizes.size());
    std::vector<std::size_t> stack{s};
    group[s] = g;
    std::size_t size = 0;
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      ++size;
      for (std::size_t u = 0; u < n; ++u)
        if (joined[v][u] && group[u] < 0) {
          group[u] = g;
          stack.push_back(u);
        }
    }
    sizes.push_back(size);
  }
  const auto best = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  std::vector<bool> mask(n);
  for (std::size_t v = 0; v < n; ++v) mask[v] = group[v] == best;
  return mask;
}

}  // namespace

FreeSpace::FreeSpace(const robot::OccupancyGrid& map, double clearance)
    : map_(map),
      clearance_(checked_clearance(clearance)),
      field_(walls_of(map), std::max(3.0, 2.0 * clearance)) {}

double FreeSpace::border_distance(const Vec<2>& p) const {
  const Vec<2> lo = map_.origin();
  const Vec<2> hi = lo + map_.resolution() * Vec<2>(map_.width(), map_.height());
  return std::min({p.x() - lo.x(), hi.x() - p.x(), p.y() - lo.y(), hi.y() - p.y()});
}

double FreeSpace::room(const Vec<2>& p) const {
  return std::min(field_.distance(p, robot::Interpolation::kBilinear), border_distance(p));
}

double FreeSpace::cell_room(int ix, int iy) const {
  return std::min(field_.cell_distance(ix, iy), border_distance(map_.cell_center(ix, iy)));
}

bool FreeSpace::allows(const Vec<2>& p) const {
  const Eigen::Vector2i c = map_.cell_of(p);
  return map_.contains(c(0), c(1)) && map_.is_free(c(0), c(1)) && room(p) >= clearance_;
}

std::optional<Vec<2>> FreeSpace::first_blocked(const Vec<2>& a, const Vec<2>& b) const {
  const double step = 0.25 * map_.resolution();
  const auto n = static_cast<long>(std::max(1.0, std::ceil((b - a).norm() / step)));
  for (long k = 0; k <= n; ++k) {
    const Vec<2> p = a + (b - a) * (static_cast<double>(k) / static_cast<double>(n));
    if (!allows(p)) return p;
  }
  return std::nullopt;
}

std::vector<Vec<2>> parse_waypoints(std::string_view text) {
  std::vector<Vec<2>> points;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t end = std::min(text.find(';', pos), text.size());
    const std::string_view item = text.substr(pos, end - pos);
    const std::size_t comma = item.find(',');
    Vec<2> p;
    if (comma == std::string_view::npos || !parse_number(item.substr(0, comma), p.x()) ||
        !parse_number(item.substr(comma + 1), p.y()))
      throw InvalidArgument(fmt::format(
          "--waypoints: expected points 'x1,y1;x2,y2;...' of finite numbers [m], got '{}' as "
          "point {} of '{}'",
          printable(item, 40), points.size() + 1, printable(text)));
    points.push_back(p);
    if (end == text.size()) break;
    pos = end + 1;
  }
  require(points.size() >= 2,
          "--waypoints: expected at least 2 points 'x1,y1;x2,y2;...', got {} in '{}'",
          points.size(), printable(text));
  return points;
}

std::vector<Vec<2>> automatic_tour(const FreeSpace& space, const std::string& map_name) {
  const double spacing = std::max(kMinSpacing, 4.0 * space.clearance());
  const std::vector<Vec<2>> places = pick_places(space, spacing);
  require(!places.empty(),
          "{}: expected free space for the robot, got no free cell {} m (--clearance) from the "
          "occupied and unknown cells and the border; lower --clearance or check the map",
          map_name, space.clearance());
  const std::size_t n = places.size();
  std::vector<std::vector<bool>> joined(n, std::vector<bool>(n, false));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      joined[i][j] = joined[j][i] = !space.first_blocked(places[i], places[j]).has_value();
  const std::vector<bool> group = largest_group(joined);
  // Only places of the group stay joined: the tree cannot leave it.
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) joined[i][j] = joined[i][j] && group[i];
  const auto root = static_cast<int>(std::find(group.begin(), group.end(), true) - group.begin());
  Tree t{std::vector<int>(n, -1), std::vector<int>(n, -1), {}};
  t.depth[static_cast<std::size_t>(root)] = 0;
  grow(places, joined, root, t);
  require(t.order.size() >= 2,
          "{}: expected two places at least {} m apart joined by a clear straight segment "
          "(--clearance {} m), found {} place{} and none joined; give the path with --waypoints",
          map_name, spacing, space.clearance(), n, n == 1 ? "" : "s");
  std::vector<Vec<2>> tour{places[static_cast<std::size_t>(root)]};
  auto go = [&](int u, int w) {
    if (joined[static_cast<std::size_t>(u)][static_cast<std::size_t>(w)]) {
      tour.push_back(places[static_cast<std::size_t>(w)]);
      return;
    }
    for (int v : tree_path(t, u, w)) tour.push_back(places[static_cast<std::size_t>(v)]);
  };
  for (std::size_t k = 1; k < t.order.size(); ++k) go(t.order[k - 1], t.order[k]);
  go(t.order.back(), root);
  return tour;
}

}  // namespace implicit::app
