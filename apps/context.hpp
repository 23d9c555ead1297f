#pragma once
// What every experiment run receives from the command line: seed, output folder, threads,
// verbosity, and a progress reporter. Experiments never print to stdout (that is for --json).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

#include <fmt/ostream.h>
#include <nlohmann/json_fwd.hpp>

#include "implicit/core/output_file.hpp"

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
  /// Throws implicit::InvalidArgument naming --out (create_out_dir) when it cannot be made.
  std::filesystem::path csv_path(const std::string& name) const;
};

/// Creates `dir`, the folder of --out, with its parents. Throws implicit::InvalidArgument naming
/// --out, the folder and why (a file of that name, a read-only or virtual file system, ...):
/// the raw filesystem error named neither the flag nor what was expected.
void create_out_dir(const std::filesystem::path& dir);

/// SIGINT and SIGTERM: stop the child process being waited for (run_child_process) and wait for
/// it, remove the outputs being written (their temporary files, OutputFile in
/// implicit/core/output_file.hpp), say on stderr how many were completed (those are kept), and
/// exit with 128 + the signal number. Called by main().
void install_signal_handlers();

/// Runs `args` (args[0] a path, or a name looked up in PATH) with stdout and stderr into `log`, in
/// a process group of its own, and waits for it; returns its exit code (128 + the signal when a
/// signal ended it, 127 when it could not be started, the reason then in `log`). A SIGINT or
/// SIGTERM to this program stops that process group and waits for it before the program exits,
/// so that no child (a plot script) keeps writing into the output folder after the command ended.
int run_child_process(const std::vector<std::string>& args, const std::filesystem::path& log);

/// Prints a subcommand's result on stdout as JSON, with the version and commit of this build.
void print_json(nlohmann::json result);

/// A run that scored nothing must not look like a result. Each key of `finite` must be a finite
/// number in `result` and each of `positive` a number > 0; otherwise a warning on stderr names
/// them (the JSON shows them as null or 0) and, unless `allow_empty`, the run fails with exit
/// code 1 (CLI::RuntimeError, thrown after the outputs were written so they can be inspected).
void require_scored(const nlohmann::json& result, const std::string& command,
                    const std::vector<std::string>& finite,
                    const std::vector<std::string>& positive, bool allow_empty);

}  // namespace implicit::app

namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace implicit::app {
/// Adds the options every subcommand shares: --seed, --json, --out, --threads, --quiet, --resume.
/// Set ctx.out_dir before the call to give --out a default (shown in --help).
void add_common_options(CLI::App& sub, RunContext& ctx);

/// The range check of a numeric flag: like CLI::Range, but NaN and inf are refused (CLI::Range
/// lets NaN through, since every comparison with it is false) and an integer flag given "3.7" or
/// "1e3" is told it needs an integer. The message names the accepted range.
///   sub.add_option("--runs", s.runs, "Runs")->check(in_range(1, 100000));
CLI::Validator in_range(int lo, int hi);
CLI::Validator in_range(double lo, double hi);

/// Appends an "Examples:" block to the subcommand's --help, one command per line:
///   set_examples(sub, {"implicit slit --samples 50 --runs 100",
///                      "implicit slit --mode paper --json > slit.json"});
void set_examples(CLI::App& sub, const std::vector<std::string>& commands);
}  // namespace implicit::app
