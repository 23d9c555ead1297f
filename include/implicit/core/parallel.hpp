#pragma once
// Deterministic parallel loops over particles or samples.
//
// parallel_for(n, f) calls f(i) for i = 0..n-1 on TBB's worker threads. It is deterministic as
// long as f(i) writes only to slot i and draws its randomness from a stream keyed by i
// (implicit::Rng): then the result is bit-identical for 1 and N threads. Reductions (sums of
// weights, means) are done afterwards, serially, in index order.

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <memory>

namespace implicit {

/// Calls f(i) for every i in [0, n), in parallel. `grain` is the smallest chunk handed to a thread.
template <typename F>
void parallel_for(std::size_t n, F&& f, std::size_t grain = 16) {
  if (n == 0) return;
  if (n <= grain) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                    });
}

/// Limits the number of worker threads while alive (0 = leave TBB's default).
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads) {
    if (threads > 0)
      control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       static_cast<std::size_t>(threads));
  }

 private:
  std::unique_ptr<tbb::global_control> control_;
};

/// Number of threads TBB would use now.
inline int active_threads() {
  return static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace implicit
