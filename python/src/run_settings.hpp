#pragma once
// The settings of the one-call runners implicit.mcl.run and implicit.slam.run, converted from the
// Python keywords into the tool's settings structs and checked against the ranges of the tool's
// flags (apps/cmd_mcl.cpp, apps/cmd_slam.cpp, apps/context.cpp): a value the command line
// refuses is refused here too, as InvalidArgument (ValueError) naming the keyword and the range,
// before a run starts.
#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <string>

#include "common.hpp"
#include "experiments/landmark_mcl.hpp"
#include "experiments/landmark_slam.hpp"
#include "experiments/run_context.hpp"

namespace implicit::python {

/// progress= of mcl.run, slam.run and da.run: the user's progress(done, total), or None. The hook
/// also checks for Ctrl-C (only the main thread sees signals; it runs tasks too). Calls come from
/// the run's workers, serialised by the bar (run_context.hpp); the interpreter's lock is taken
/// for each.
struct PythonProgress {
  py::object callable;
  std::exception_ptr error;  ///< the callback's exception (or Ctrl-C's), as raised

  void operator()(std::size_t done, std::size_t total) {
    py::gil_scoped_acquire locked;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!callable.is_none()) callable(done, total);
    } catch (...) {
      error = std::current_exception();
      throw;
    }
  }
};

/// Runs fn() with `progress` (the user's callable or None, checked first) as ctx's progress hook.
/// The experiments catch a failed run's exception and report it as a message
/// (parallel_runs.hpp), so the callback's own exception is kept and raised unchanged in place of
/// whatever the run then throws.
template <typename Fn>
auto with_python_progress(experiments::RunContext& ctx, const py::object& progress, Fn&& fn) {
  require(progress.is_none() || PyCallable_Check(progress.ptr()) != 0,
          "progress: expected a callable progress(done, total) or None, got {}",
          type_name(progress));
  auto state = std::make_shared<PythonProgress>();
  state->callable = progress;
  ctx.progress = [state](std::size_t done, std::size_t total) { (*state)(done, total); };
  try {
    return fn();
  } catch (...) {
    if (state->error) std::rethrow_exception(state->error);
    throw;
  }
}

/// One numeric setting: the Python keyword, the tool's flag and the range of its CLI11 check
/// (in_range(lo, hi)); `count` > 0 for a list of that many values (each in the range).
struct RunSettingRange {
  const char* key;
  const char* flag;
  double lo;
  double hi;
  bool integer;
  int count = 0;
};

/// The ranges of implicit.mcl.run ("mcl") or implicit.slam.run ("slam"), including the common
/// `threads`; tests compare them with the tool's --help.
std::span<const RunSettingRange> run_setting_ranges(const std::string& command);

experiments::MclSettings mcl_settings(const py::dict& kw);
experiments::SlamSettings slam_settings(const py::dict& kw);

/// The common settings of every runner: seed (--seed: [0, 2^64 - 1]), out (None: no files),
/// threads (--threads: [0, 1024]) and verbose (True: the tool's progress bar on stderr, as
/// without --json; False: nothing on stderr but warnings).
experiments::RunContext run_context(const py::handle& seed, const py::handle& out,
                                    const py::handle& threads,
                                    const py::handle& verbose = py::bool_(false));

}  // namespace implicit::python
