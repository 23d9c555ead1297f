#pragma once
// A known map of point landmarks with user ids (e.g. the 15 surveyed beacons of the Car Park).
//
//   LandmarkMap map;
//   map.add(1, Landmark(2.9, -4.0));
//   int k = map.index_of(1);             // position in the map, -1 if the id is unknown
//   const Landmark& m = map.position(k);
//
// Ids are arbitrary non-negative integers (file ids); filters work with positions 0..size()-1.

#include <cstddef>
#include <unordered_map>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

class LandmarkMap {
 public:
  /// Adds a landmark; throws InvalidArgument for a duplicate or negative id or a non-finite
  /// position.
  void add(int id, const Landmark& position) {
    require(id >= 0, "landmark map: expected a non-negative landmark id, got {}", id);
    require(position.allFinite(),
            "landmark map: expected a finite position for landmark {}, got ({}, {})", id,
            position(0), position(1));
    require(index_of(id) < 0, "landmark map: expected unique landmark ids, got {} twice", id);
    index_.emplace(id, static_cast<int>(ids_.size()));
    ids_.push_back(id);
    positions_.push_back(position);
  }

  std::size_t size() const { return positions_.size(); }
  bool empty() const { return positions_.empty(); }
  const Landmark& position(std::size_t k) const { return positions_[k]; }
  int id(std::size_t k) const { return ids_[k]; }
  const std::vector<Landmark>& positions() const { return positions_; }

  /// Position in the map of the landmark with this id, or -1.
  /// Hashed, so that reading a log with many landmarks stays linear in its length.
  int index_of(int id) const {
    const auto it = index_.find(id);
    return it == index_.end() ? -1 : it->second;
  }

 private:
  std::vector<int> ids_;
  std::vector<Landmark> positions_;
  std::unordered_map<int, int> index_;  ///< id -> position in ids_ and positions_
};

}  // namespace implicit::robot
