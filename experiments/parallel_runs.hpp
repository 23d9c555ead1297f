#pragma once
// The independent runs of an experiment (seeds, data sets), spread over the processes of an MPI
// job and the threads of each process, with every result the same as in one process.
//
// Every process ("rank") executes the whole command; distribute_runs() is the one place where
// they divide the work: each rank computes some runs (static: run i on rank i mod N; dynamic:
// ranks take the next runs from a shared counter as they finish), then every rank receives every
// run's record, so the aggregation after the loop is the same code on the same numbers everywhere
// and the JSON, CSV and report of rank 0 equal those of a single process. Ranks other than 0
// write into a private temporary folder and print nothing.
//
//   const auto records = distribute_runs(ctx, "slam", settings_text, n, [&](std::size_t i) {
//     const auto m = evaluate(run_filter(data(i), seed + i));
//     SlamRunRecord r;                 // a named record (run_record.hpp)
//     r.error_percent = m.error_percent;
//     return r;
//   });
//   records[0].error_percent;
//
// A record moves bit-exactly (its numbers in the order of its field table: binary between ranks,
// hexadecimal floating point in files). When --out is set, each record is also written to
// <out>/.resume/<experiment>-<hash>/<run>.rec as soon as its run finishes; with --resume those
// runs are read back instead of being recomputed (a file that is not a record of that type is
// named on stderr and its run computed again). A run that throws does not stop the others:
// after the loop, distribute_runs throws one error naming every failed run and its message.

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "experiments/run_context.hpp"
#include "experiments/run_record.hpp"

namespace implicit::experiments {

/// The untyped loop under distribute_runs: run(i) returns record_values of run i's record and
/// `check` says why numbers read back from a --resume file are not such a record (empty: they
/// are).
std::vector<RecordValues> distribute_run_values(
    const RunContext& ctx, const std::string& experiment, const std::string& settings,
    std::size_t n, const std::function<RecordValues(std::size_t)>& run,
    const std::function<std::string(const RecordValues&)>& check);

/// Runs run(i) for i in [0, n) over the ranks and threads; returns the n records (each a
/// NamedRecord, run_record.hpp) in run order. `experiment` and `settings` identify the loop for
/// --resume (settings: every option the records depend on, including the seed). Throws after the
/// loop if any run threw.
template <typename Run, NamedRecord R = std::invoke_result_t<const Run&, std::size_t>>
std::vector<R> distribute_runs(const RunContext& ctx, const std::string& experiment,
                               const std::string& settings, std::size_t n, const Run& run) {
  const std::vector<RecordValues> values = distribute_run_values(
      ctx, experiment, settings, n, [&](std::size_t i) { return record_values<R>(run(i)); },
      [](const RecordValues& v) {
        R r;
        return record_from_values(v, r);
      });
  std::vector<R> records(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Checked already: every value came from record_values or passed `check`.
    const std::string why = record_from_values(values[i], records[i]);
    if (!why.empty()) throw std::logic_error(fmt::format("{} run {}: {}", experiment, i, why));
  }
  return records;
}

/// The process's place in the job: MPI is started when the program runs under an MPI launcher
/// (mpirun, srun) in a build with IMPLICIT_WITH_MPI, and stopped by finish(). On ranks other
/// than 0 the command line's --out is replaced by a private temporary folder and stdout and
/// stderr are silenced; argv() is the command line to parse.
class RankSession {
 public:
  RankSession(int argc, char** argv);
  ~RankSession();
  RankSession(const RankSession&) = delete;
  RankSession& operator=(const RankSession&) = delete;
  int argc() const { return static_cast<int>(pointers_.size()) - 1; }
  char** argv() { return pointers_.data(); }
  /// The exit code of the job: `code` on every rank; a rank that fails alone stops the job.
  int finish(int code);

 private:
  std::vector<std::string> args_;
  std::vector<char*> pointers_;
  std::string private_dir_;
};

/// Rank of this process and number of ranks (0 and 1 without MPI).
int rank_index();
int rank_count();

}  // namespace implicit::experiments
