#pragma once
// What every experiment run receives from the command line: seed, output folder, threads,
// verbosity, and a progress reporter. Experiments never print to stdout (that is for --json).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

namespace implicit::app {

/// Progress on stderr: a bar with ETA when stderr is a terminal, plain lines otherwise,
/// nothing when disabled (--quiet or --json). Thread-safe: tick() may be called from workers.
///
///   Progress bar("MCL runs", runs, ctx.show_progress());
///   parallel_for(runs, [&](std::size_t r) { ...; bar.tick(); });
///
/// Style::kLines prints one line per tick whatever stderr is: for an outer loop whose items
/// draw their own bars (`implicit reproduce`), so the two never share a terminal line.
class Progress {
 public:
  enum class Style { kAuto, kLines };
  Progress(std::string label, std::size_t total, bool enabled, Style style = Style::kAuto);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void tick(std::size_t n = 1);
  /// Like tick(n), and names what comes next in the printed line ("next: slit M=50").
  void tick(std::size_t n, const std::string& note);
  void finish();

 private:
  void draw(std::size_t done, bool final, const std::string& note = {});
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
};

struct RunContext {
  std::uint64_t seed = 1;
  std::filesystem::path out_dir;  ///< where CSV files go; empty = write none
  int threads = 0;                ///< 0 = all cores
  bool quiet = false;             ///< no progress output
  bool json = false;              ///< --json mode: nothing extra on stderr either
  bool resume = false;            ///< reuse the runs kept in out_dir/.resume (parallel_runs.hpp)

  bool show_progress() const { return !quiet && !json; }
  /// Path of a CSV file in out_dir (creates the folder); empty path when out_dir is empty.
  std::filesystem::path csv_path(const std::string& name) const;
};

}  // namespace implicit::app

namespace CLI {
class App;
}

namespace implicit::app {
/// Adds the options every subcommand shares: --seed, --json, --out, --threads, --quiet, --resume.
/// Set ctx.out_dir before the call to give --out a default (shown in --help).
void add_common_options(CLI::App& sub, RunContext& ctx);

/// Appends an "Examples:" block to the subcommand's --help, one command per line:
///   set_examples(sub, {"implicit slit --samples 50 --runs 100",
///                      "implicit slit --mode paper --json > slit.json"});
void set_examples(CLI::App& sub, const std::vector<std::string>& commands);
}  // namespace implicit::app
