#pragma once
// Counter-based random streams.
//
// Every random draw in the project comes from a stream addressed by (seed, step, index, purpose):
// a particle's draws at a filter step, a sample's reference variable, a run's process noise.
// The engine is Random123's Philox4x64-10, a keyed bijection of a counter, so a stream needs no
// state shared with any other stream: results do not depend on thread count or evaluation order.
//
//   using implicit::purpose::kProposal;
//   implicit::Rng rng({.seed = 42, .step = n, .index = j, .purpose = kProposal});
//   double u = rng.uniform();      // in (0, 1), 53 random bits
//   double z = rng.normal();       // standard normal (Box-Muller, our own transform)
//
// The uniform and normal transforms are the project's own because std::normal_distribution and
// friends differ between standard libraries, which would make golden numbers unportable.

#include <Random123/philox.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/types.hpp"

namespace implicit {

/// Address of one random stream. Two different keys give statistically independent streams.
struct StreamKey {
  std::uint64_t seed = 0;     ///< user seed (one per experiment or run)
  std::uint64_t step = 0;     ///< time step, iteration, or run number
  std::uint64_t index = 0;    ///< particle or sample index
  std::uint64_t purpose = 0;  ///< what the draws are for (see implicit::purpose)
};

/// Conventional `purpose` values, so that different uses of one (seed, step, index) never overlap.
namespace purpose {
inline constexpr std::uint64_t kReference = 1;     ///< reference variables xi of implicit sampling
inline constexpr std::uint64_t kResampling = 2;    ///< uniforms of a resampling step
inline constexpr std::uint64_t kProcessNoise = 3;  ///< noise of a simulated system
inline constexpr std::uint64_t kInitial = 4;       ///< initial particle cloud
inline constexpr std::uint64_t kProposal = 5;      ///< draws of a proposal (e.g. bootstrap)
inline constexpr std::uint64_t kMixture = 6;       ///< mixture component choice
inline constexpr std::uint64_t kData = 7;          ///< synthetic data generation
inline constexpr std::uint64_t kRecovery = 8;      ///< injection choices and draws of recovery
inline constexpr std::uint64_t kGlobalInit = 9;    ///< draws of a global initialisation
inline constexpr std::uint64_t kUser = 1000;       ///< first value free for user code
}  // namespace purpose

/// A random stream: uniforms and standard normals from one StreamKey.
class Rng {
 public:
  explicit Rng(const StreamKey& key) {
    key_ = {{key.seed, key.purpose}};
    ctr_ = {{key.step, key.index, 0, 0}};
  }

  /// Uniform in the open interval (0, 1) with 53 random bits.
  double uniform() {
    if (pos_ == 4) refill();
    const std::uint64_t bits = out_.v[pos_++];
    return (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53;
  }

  /// Standard normal by the Box-Muller transform (pairs are generated; the second is cached).
  double normal() {
    if (has_cached_) {
      has_cached_ = false;
      return cached_;
    }
    const double u1 = uniform();
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * kPi * u2;
    cached_ = r * std::sin(angle);
    has_cached_ = true;
    return r * std::cos(angle);
  }

  /// Fills every entry of `out` with independent standard normals.
  template <typename Derived>
  void fill_normal(Eigen::MatrixBase<Derived>& out) {
    for (Eigen::Index j = 0; j < out.cols(); ++j)
      for (Eigen::Index i = 0; i < out.rows(); ++i) out(i, j) = normal();
  }

  /// A vector of N standard normals (dim is used when N is Eigen::Dynamic).
  template <int N>
  Vec<N> normal_vector(int dim = N) {
    Vec<N> v(dim);
    fill_normal(v);
    return v;
  }

 private:
  void refill() {
    out_ = engine_(ctr_, key_);
    ++ctr_.v[2];  // block counter within the stream
    pos_ = 0;
  }

  using Engine = r123::Philox4x64;
  Engine engine_;
  Engine::key_type key_;
  Engine::ctr_type ctr_;
  Engine::ctr_type out_{};
  int pos_ = 4;
  bool has_cached_ = false;
  double cached_ = 0.0;
};

/// Standard normal vectors drawn in order from one stream and kept, so that after rewind() the
/// same vectors come again: common random numbers for the central differences of an estimator
/// (the same references at x and at every x +- h) without paying the Box-Muller transform again,
/// which dominated a path integral control estimate. Past `max_kept` doubles it keeps nothing
/// and rewind() restarts the stream instead: the numbers are the same either way.
class ReplayableNormals {
 public:
  explicit ReplayableNormals(const StreamKey& key, std::size_t max_kept = std::size_t{1} << 21)
      : key_(key), rng_(key), max_kept_(max_kept) {}

  /// Back to the first vector.
  void rewind() {
    position_ = 0;
    if (!keeping_) {
      rng_ = Rng(key_);
      drawn_ = 0;
    }
  }

  /// The next vector (of xi's size; xi is a vector) in the sequence.
  template <typename Derived>
  void next(Eigen::MatrixBase<Derived>& xi) {
    const auto size = static_cast<std::size_t>(xi.size());
    if (position_ < drawn_) {  // replay (only while keeping)
      for (std::size_t i = 0; i < size; ++i)
        xi(static_cast<Eigen::Index>(i)) = kept_[position_ + i];
      position_ += size;
      return;
    }
    rng_.fill_normal(xi);
    position_ += size;
    drawn_ = position_;
    if (!keeping_) return;
    if (kept_.size() + size > max_kept_) {  // too many to keep: forget them, restart on rewind
      keeping_ = false;
      kept_ = {};
      return;
    }
    for (std::size_t i = 0; i < size; ++i) kept_.push_back(xi(static_cast<Eigen::Index>(i)));
  }

 private:
  StreamKey key_;
  Rng rng_;
  std::size_t max_kept_;
  std::vector<double> kept_;
  std::size_t position_ = 0, drawn_ = 0;  // in doubles
  bool keeping_ = true;
};

}  // namespace implicit
