#pragma once
// What every experiment run receives from its caller (the command line, Python, a benchmark):
// seed, output folder, threads, verbosity, and a progress reporter. Experiments never print to
// stdout (that is for --json).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>

#include "implicit/core/output_file.hpp"

namespace implicit::experiments {

/// A caller's view of progress (Python's progress=): called with (done, total) in the units of
/// the run's bar, at most every 100 ms, with monotone counts, and once with (total, total) when
/// the run completes. Calls are serialised but may come from any worker thread. Throwing stops
/// the run: the exception reaches the caller of the experiment (the runs catch and report
/// failures, so the caller keeps the original exception itself; python/src/runs.cpp).
using ProgressHook = std::function<void(std::size_t done, std::size_t total)>;

/// Thrown by ProgressBar::tick and check() once the hook has thrown: the other workers stop at
/// their next tick, or before their next run, instead of finishing every run.
class RunStopped : public std::runtime_error {
 public:
  RunStopped() : std::runtime_error("run stopped by its progress callback") {}
};

/// Progress on stderr: a bar with ETA when stderr is a terminal, plain lines otherwise,
/// nothing when disabled (--quiet or --json). Thread-safe: tick() may be called from workers.
///
///   ProgressBar bar("MCL runs", runs, ctx.show_progress());
///   parallel_for(runs, [&](std::size_t r) { ...; bar.tick(); });
///
/// Style::kLines prints one line per tick whatever stderr is: for an outer loop whose items
/// draw their own bars (`implicit reproduce`), so the two never share a terminal line.
class ProgressBar {
 public:
  enum class Style { kAuto, kLines };
  ProgressBar(std::string label, std::size_t total, bool enabled, Style style = Style::kAuto);
  /// The same, also reporting to `hook` (see ProgressHook) when it is set.
  ProgressBar(std::string label, std::size_t total, bool enabled, ProgressHook hook);
  /// Draws the final line only: the hook's final call is finish()'s, never a destructor's, which
  /// may run while an exception unwinds (and must not throw).
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void tick(std::size_t n = 1);
  /// Like tick(n), and names what comes next in the printed line ("next: slit M=50").
  void tick(std::size_t n, const std::string& note);
  /// Draws the final line and reports (total, total) to the hook, once.
  void finish();
  /// Throws RunStopped when the hook has thrown: called before a run starts, so that runs
  /// whose progress ticks only at their end do not start after a stop.
  void check() const;

 private:
  /// Calls the hook with the count read under its lock (monotone), throttled unless `final`.
  void report(bool final);
  /// Prints the count at the time it holds the lock, so printed counts never decrease.
  void draw(bool final, const std::string& note = {});
  std::string label_;
  std::size_t total_;
  bool enabled_;
  bool tty_;
  bool every_tick_ = false;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_percent_ = -1;
  bool finished_ = false;
  ProgressHook hook_;
  std::mutex hook_mutex_;
  std::chrono::steady_clock::time_point last_report_;
  std::size_t reported_ = 0;
  bool reported_any_ = false;
  std::atomic<bool> stopped_{false};
};

struct RunContext {
  std::uint64_t seed = 1;
  std::filesystem::path out_dir;  ///< where CSV files go; empty = write none
  int threads = 0;                ///< 0 = all cores
  bool quiet = false;             ///< no progress output
  bool json = false;              ///< --json mode: nothing extra on stderr either
  bool resume = false;            ///< reuse the runs kept in out_dir/.resume (parallel_runs.hpp)
  ProgressHook progress;          ///< optional; empty = none (Python's progress=)

  bool show_progress() const { return !quiet && !json; }
  /// Path of a CSV file in out_dir (creates the folder); empty path when out_dir is empty.
  /// Throws implicit::InvalidArgument naming --out (create_out_dir) when it cannot be made.
  std::filesystem::path csv_path(const std::string& name) const;
};

/// Creates `dir`, the folder of --out, with its parents. Throws implicit::InvalidArgument naming
/// --out, the folder and why (a file of that name, a read-only or virtual file system, ...):
/// the raw filesystem error named neither the flag nor what was expected.
void create_out_dir(const std::filesystem::path& dir);

}  // namespace implicit::experiments
