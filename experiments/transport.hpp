#pragma once
// What experiments/parallel_runs.cpp needs from the processes of a job. Two implementations, chosen
// at link time: local.cpp (one process) and mpi.cpp (MPI, in the IMPLICIT_WITH_MPI build).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace implicit::experiments::transport {

/// Starts MPI when the process was launched by an MPI launcher; returns whether it did.
bool start(int* argc, char*** argv);
void stop();
/// Stops every process of the job with this exit code (after a failure on one rank only).
[[noreturn]] void abort_job(int code);
int rank();
int size();

/// The largest exit code of all ranks, returned on every rank. A rank that does not arrive within
/// `timeout_seconds` failed alone (the others wait for it in a collective): the job is stopped.
int agree_exit_code(int code, double timeout_seconds);

/// Every rank's `local` bytes, concatenated in rank order, on every rank.
std::string all_gather(const std::string& local);
/// Rank 0's `data` on every rank.
std::string broadcast(const std::string& data);

/// A counter shared by the ranks, for dynamic assignment: take(k) returns the counter's value and
/// adds k to it, atomically. Constructed and destroyed by every rank at the same point.
class SharedCounter {
 public:
  SharedCounter();
  ~SharedCounter();
  SharedCounter(const SharedCounter&) = delete;
  SharedCounter& operator=(const SharedCounter&) = delete;
  std::uint64_t take(std::uint64_t k);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace implicit::experiments::transport
