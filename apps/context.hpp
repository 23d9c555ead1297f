#pragma once
// What the command line adds to an experiment's RunContext (experiments/run_context.hpp): the
// signal handlers, child processes, the JSON on stdout, and the CLI11 option helpers.

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

#include "experiments/run_context.hpp"
#include "implicit/core/output_file.hpp"

namespace implicit::app {

// The experiments layer's run context and progress bar, by their names here too.
using experiments::create_out_dir;
using Progress = experiments::ProgressBar;
using experiments::RunContext;

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
