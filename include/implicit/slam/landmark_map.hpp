#pragma once
// Copy-on-write landmark maps for particle SLAM: a persistent array with path copying.
//
// A particle filter for SLAM carries one map per particle. Resampling duplicates particles; with
// plain vectors every duplicate deep-copies its whole map (O(N) per particle per resampling), and
// most of those copies are identical. PersistentArray<T> is an immutable B-ary tree of fixed-size
// chunks held by shared pointers (Montemerlo's FastSLAM "landmark tree", as a radix tree over the
// landmark index):
//   * copying a map is O(1): the copy shares every node with the original;
//   * set(i, v) and push_back(v) copy only the root-to-leaf path of index i, O(B log_B N), and
//     leave every other holder of the old version untouched;
//   * get(i) is O(log_B N); for_each visits the items in index order.
//
//   PersistentArray<LandmarkEstimate> a;     // empty
//   a.push_back({mean, cov});                // landmark 0
//   PersistentArray<LandmarkEstimate> b = a;  // O(1), shares storage
//   b.set(0, updated);                       // a still holds the old landmark 0
//
// Mistakes to avoid: keeping a reference returned by get() across a set() on the SAME object
// (the node may be replaced); mutating through const_cast (every sharer would see it). Reference
// counts are atomic, so distinct PersistentArray objects that share nodes may be used from
// different threads; one object must not be written from two threads at once.

#include <array>
#include <cstddef>
#include <memory>
#include <unordered_set>
#include <utility>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"

namespace implicit::slam {

/// One landmark of a particle's map: a Gaussian N(mean, cov) (cov = 0 for point landmarks).
struct LandmarkEstimate {
  Vec<2> mean = Vec<2>::Zero();  ///< (east, north) [m]
  Mat<2> cov = Mat<2>::Zero();   ///< 2x2 covariance [m^2]
};

template <typename T, int B = 8>
class PersistentArray {
  static_assert(B >= 2 && (B & (B - 1)) == 0, "branching factor must be a power of two");

 public:
  using value_type = T;
  static constexpr int kBranching = B;

  PersistentArray() = default;

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  const T& get(std::size_t i) const {
    require(i < size_, "landmark map: expected an index below {}, got {}", size_, i);
    const void* node = root_.get();
    for (int level = depth_; level > 0; --level)
      node = static_cast<const Internal*>(node)->child[digit(i, level)].get();
    return static_cast<const Leaf*>(node)->item[digit(i, 0)];
  }
  const T& operator[](std::size_t i) const { return get(i); }

  /// Replaces item i, copying the nodes on its path (other versions keep the old item).
  void set(std::size_t i, const T& value) {
    require(i < size_, "landmark map: expected an index below {}, got {}", size_, i);
    root_ = set_rec(root_, depth_, i, value);
  }

  /// Appends an item (index size()), growing the tree by one level when it is full.
  void push_back(const T& value) {
    if (size_ == capacity(depth_) && size_ > 0) {
      auto up = std::make_shared<Internal>();
      up->child[0] = std::move(root_);
      root_ = std::move(up);
      ++depth_;
    }
    ++size_;
    root_ = set_rec(root_, depth_, size_ - 1, value);
  }

  /// Calls f(index, item) for every item in index order.
  template <typename F>
  void for_each(F&& f) const {
    if (size_ > 0) visit(root_.get(), depth_, 0, f);
  }

  /// Bytes held by this map's nodes that are NOT in `seen` (adds them to `seen`). Summing over
  /// all particles with one `seen` set gives the memory of the whole population.
  std::size_t unique_bytes(std::unordered_set<const void*>& seen) const {
    return size_ > 0 ? bytes_rec(root_.get(), depth_, seen) : 0;
  }

  /// True when both hold the very same root node (no copy happened since they were shared).
  bool shares_root_with(const PersistentArray& other) const { return root_ == other.root_; }

  static constexpr std::size_t leaf_bytes() { return sizeof(Leaf); }
  static constexpr std::size_t internal_bytes() { return sizeof(Internal); }

 private:
  struct Leaf {
    std::array<T, B> item{};
  };
  struct Internal {
    std::array<std::shared_ptr<const void>, B> child{};
  };

  static constexpr int kBits = [] {
    int b = 0;
    while ((1 << b) < B) ++b;
    return b;
  }();

  static std::size_t digit(std::size_t i, int level) {
    return (i >> (kBits * level)) & static_cast<std::size_t>(B - 1);
  }
  static std::size_t capacity(int depth) { return std::size_t{1} << (kBits * (depth + 1)); }

  static std::shared_ptr<const void> set_rec(const std::shared_ptr<const void>& node, int level,
                                             std::size_t i, const T& value) {
    if (level == 0) {
      auto leaf = node ? std::make_shared<Leaf>(*static_cast<const Leaf*>(node.get()))
                       : std::make_shared<Leaf>();
      leaf->item[digit(i, 0)] = value;
      return leaf;
    }
    auto in = node ? std::make_shared<Internal>(*static_cast<const Internal*>(node.get()))
                   : std::make_shared<Internal>();
    auto& c = in->child[digit(i, level)];
    c = set_rec(c, level - 1, i, value);
    return in;
  }

  template <typename F>
  void visit(const void* node, int level, std::size_t base, F& f) const {
    if (level == 0) {
      const auto* leaf = static_cast<const Leaf*>(node);
      for (int k = 0; k < B && base + k < size_; ++k) f(base + k, leaf->item[k]);
      return;
    }
    const auto* in = static_cast<const Internal*>(node);
    const std::size_t span = std::size_t{1} << (kBits * level);
    for (int k = 0; k < B && base + k * span < size_; ++k)
      visit(in->child[k].get(), level - 1, base + k * span, f);
  }

  static std::size_t bytes_rec(const void* node, int level, std::unordered_set<const void*>& seen) {
    if (node == nullptr || !seen.insert(node).second) return 0;
    if (level == 0) return sizeof(Leaf);
    std::size_t total = sizeof(Internal);
    for (const auto& c : static_cast<const Internal*>(node)->child)
      total += bytes_rec(c.get(), level - 1, seen);
    return total;
  }

  std::shared_ptr<const void> root_;
  std::size_t size_ = 0;
  int depth_ = 0;  ///< number of internal levels above the leaves
};

/// The map of one particle: its landmark estimates, shared with its copies until written
/// (robot::LandmarkMap is a known map of landmark positions).
using LandmarkEstimates = PersistentArray<LandmarkEstimate>;

}  // namespace implicit::slam
