// distribute_run_values() (under distribute_runs) and RankSession (experiments/parallel_runs.hpp).
#include "experiments/parallel_runs.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include "experiments/transport.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/version.hpp"

namespace implicit::experiments {
namespace {

namespace fs = std::filesystem;

// Where the finished runs are kept: the --out of the command line as the user gave it (ranks
// other than 0 see a private folder in ctx.out_dir), or reproduce's default.
fs::path g_resume_root;

// ---- Records between ranks: index, status, then the numbers or the error message ------------

struct Outcome {
  bool done = false;
  bool failed = false;
  bool invalid = false;  ///< failed with InvalidArgument (the data or settings, not the machine)
  RecordValues record;
  std::string error;
};

template <typename T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T get(const std::string& in, std::size_t& at) {
  T v;
  std::memcpy(&v, in.data() + at, sizeof(T));
  at += sizeof(T);
  return v;
}

void pack(std::string& out, std::size_t index, const Outcome& o) {
  put<std::uint64_t>(out, index);
  put<std::uint8_t>(out, o.failed ? (o.invalid ? 2 : 1) : 0);
  if (o.failed) {
    put<std::uint64_t>(out, o.error.size());
    out += o.error;
  } else {
    put<std::uint64_t>(out, o.record.size());
    out.append(reinterpret_cast<const char*>(o.record.data()), o.record.size() * sizeof(double));
  }
}

void unpack(const std::string& in, std::vector<Outcome>& outcomes) {
  std::size_t at = 0;
  while (at < in.size()) {
    const auto index = get<std::uint64_t>(in, at);
    const auto state = get<std::uint8_t>(in, at);
    const bool failed = state != 0;
    const auto count = get<std::uint64_t>(in, at);
    Outcome& o = outcomes.at(index);
    o.done = true;
    o.failed = failed;
    o.invalid = state == 2;
    if (failed) {
      o.error = in.substr(at, count);
      at += count;
    } else {
      o.record.resize(count);
      std::memcpy(o.record.data(), in.data() + at, count * sizeof(double));
      at += count * sizeof(double);
    }
  }
}

// ---- Records in files: one per run, hexadecimal floating point (exact, NaN and inf too) -------

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (const unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

fs::path record_path(const fs::path& folder, std::size_t index) {
  return folder / fmt::format("{}.rec", index);
}

void write_record(const fs::path& folder, const std::string& key, std::size_t index,
                  const RecordValues& r) {
  // Written whole, then renamed (OutputFile): a run interrupted while writing leaves no record.
  try {
    OutputFile out(record_path(folder, index), OutputFile::Mode::kRecord);
    out.stream() << format_run_record(key, r);
    out.commit();
  } catch (const InvalidArgument&) {
    // A missing record only costs a recomputation with --resume.
  }
}

using Check = std::function<std::string(const RecordValues&)>;

// A missing record: false. A damaged one (a 0-byte file after a full disk, an edited one, numbers
// that are not the experiment's record): false and a warning on stderr naming the file and why,
// since its run is then computed again.
bool read_record(const fs::path& folder, const std::string& key, std::size_t index,
                 const Check& check, RecordValues& r) {
  const fs::path file = record_path(folder, index);
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return false;
  std::ifstream is(file, std::ios::binary);
  std::ostringstream text;
  text << is.rdbuf();
  std::string why = is ? parse_run_record(text.str(), key, r) : "got an unreadable file";
  if (why.empty()) why = check(r);
  if (why.empty()) return true;
  fmt::print(stderr, "implicit: --resume: {}: {}; ignored, run {} is computed again\n",
             file.string(), why, index);
  return false;
}

// ---- Assignment of the runs to this rank -----------------------------------------------------

// IMPLICIT_SCHEDULE=static|dynamic (default dynamic), as rank 0 sees it: a launcher need not pass
// the environment to every node, and ranks that disagreed would wait for each other forever.
bool dynamic_schedule() {
  std::string choice = "dynamic";
  if (const char* s = std::getenv("IMPLICIT_SCHEDULE"); s != nullptr && transport::rank() == 0)
    choice = s;
  choice = transport::broadcast(choice);
  if (choice == "dynamic" || choice == "static") return choice == "dynamic";
  throw InvalidArgument(
      fmt::format("IMPLICIT_SCHEDULE: expected static or dynamic, got '{}'", choice));
}

// IMPLICIT_FAIL_RUN=i makes run i throw: the failure path, rehearsed by tests/mpi/compare.py;
// IMPLICIT_FAIL_RUN=-2 makes every run refuse its input (InvalidArgument), as a model that does
// not match the data would (tests/apps/bad_input_cli_test.cpp).
long failing_run() {
  const char* s = std::getenv("IMPLICIT_FAIL_RUN");
  return s == nullptr ? -1 : std::strtol(s, nullptr, 10);
}

// The message without run_one's " (rank k)" suffix.
std::string without_rank(const std::string& error) {
  const std::size_t at = error.rfind(" (rank ");
  if (at == std::string::npos || error.back() != ')') return error;
  const std::string digits = error.substr(at + 7, error.size() - at - 8);
  const bool number = !digits.empty() && std::all_of(digits.begin(), digits.end(),
                                                     [](char c) { return c >= '0' && c <= '9'; });
  return number ? error.substr(0, at) : error;
}

// Called on TBB's threads: no MPI here (the ranks are started with MPI_THREAD_FUNNELED).
void run_one(std::size_t i, const std::function<RecordValues(std::size_t)>& run,
             std::vector<Outcome>& outcomes, const fs::path& folder, const std::string& key,
             const std::string& where) {
  Outcome& o = outcomes[i];
  try {
    if (static_cast<long>(i) == failing_run())
      throw std::runtime_error("failure requested by IMPLICIT_FAIL_RUN");
    if (failing_run() == -2) throw InvalidArgument("refusal requested by IMPLICIT_FAIL_RUN=-2");
    o.record = run(i);
    if (!folder.empty()) write_record(folder, key, i, o.record);
  } catch (const InvalidArgument& e) {
    o.failed = o.invalid = true;
    o.error = e.what();
  } catch (const std::exception& e) {
    o.failed = true;
    o.error = e.what();
  } catch (...) {
    o.failed = true;
    o.error = "unknown exception";
  }
  if (o.failed) o.error += where;
  o.done = true;
}

// Computes this rank's share of the runs not yet done, with TBB inside the rank.
void compute_share(std::vector<Outcome>& outcomes,
                   const std::function<RecordValues(std::size_t)>& run, const fs::path& folder,
                   const std::string& key) {
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < outcomes.size(); ++i)
    if (!outcomes[i].done) todo.push_back(i);
  const auto ranks = static_cast<std::size_t>(transport::size());
  const auto me = static_cast<std::size_t>(transport::rank());
  const std::string where = ranks > 1 ? fmt::format(" (rank {})", me) : "";
  if (!dynamic_schedule() || ranks == 1) {
    // Static: run todo[k] on rank k mod N.
    std::vector<std::size_t> mine;
    for (std::size_t k = me; k < todo.size(); k += ranks) mine.push_back(todo[k]);
    parallel_for(
        mine.size(), [&](std::size_t k) { run_one(mine[k], run, outcomes, folder, key, where); },
        1);
    return;
  }
  // Dynamic: take as many runs as this rank has threads, compute them, take the next ones; a
  // rank with slow runs (or a slow node) simply takes fewer.
  transport::SharedCounter counter;
  const auto chunk =
      static_cast<std::uint64_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  for (;;) {
    const std::uint64_t first = counter.take(chunk);
    if (first >= todo.size()) break;
    const std::size_t count = std::min<std::size_t>(chunk, todo.size() - first);
    parallel_for(
        count, [&](std::size_t k) { run_one(todo[first + k], run, outcomes, folder, key, where); },
        1);
  }
}

}  // namespace

std::vector<RecordValues> distribute_run_values(const RunContext& ctx,
                                                const std::string& experiment,
                                                const std::string& settings, std::size_t n,
                                                const std::function<RecordValues(std::size_t)>& run,
                                                const Check& check) {
  // A record is reused only by the same build: another commit may compute other numbers.
  const std::string key =
      fmt::format("{} {} runs={} commit={} format=1", experiment, settings, n, git_commit());
  require(!ctx.resume || !g_resume_root.empty(),
          "--resume: expected --out (the folder whose .resume/ keeps the finished runs), got none");
  fs::path folder;
  if (!g_resume_root.empty()) {
    folder = g_resume_root / ".resume" / fmt::format("{}-{:016x}", experiment, fnv1a(key));
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) folder.clear();
  }
  std::vector<Outcome> outcomes(n);
  if (ctx.resume && !folder.empty()) {
    // Rank 0 reads, every rank receives: all agree on which runs remain even without a shared
    // file system.
    std::string found;
    if (transport::rank() == 0)
      for (std::size_t i = 0; i < n; ++i) {
        Outcome o;
        if (read_record(folder, key, i, check, o.record)) pack(found, i, o);
      }
    unpack(transport::broadcast(found), outcomes);
  }
  std::vector<Outcome> computed(n);
  for (std::size_t i = 0; i < n; ++i) computed[i].done = outcomes[i].done;
  compute_share(computed, run, folder, key);
  std::string mine;
  for (std::size_t i = 0; i < n; ++i)
    if (computed[i].done && !outcomes[i].done) pack(mine, i, computed[i]);
  unpack(transport::all_gather(mine), outcomes);

  std::vector<RecordValues> records(n);
  std::string failures;
  std::size_t failed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (outcomes[i].failed) {
      ++failed;
      failures += fmt::format("\n  run {}: {}", i, outcomes[i].error);
    } else {
      records[i] = std::move(outcomes[i].record);
    }
  }
  // Every run refused the same input (a model that does not match the data, a setting the
  // filter checks): that message, as the error it was, instead of "n of n runs failed".
  if (failed == n && n > 0) {
    const std::string first = without_rank(outcomes[0].error);
    const bool same = std::all_of(outcomes.begin(), outcomes.end(), [&](const Outcome& o) {
      return o.invalid && without_rank(o.error) == first;
    });
    if (same) throw InvalidArgument(first);
  }
  if (failed > 0)
    throw std::runtime_error(fmt::format(
        "{}: {} of {} runs failed, no result is reported; {}{}", experiment, failed, n,
        folder.empty() ? "the other runs are lost (no --out)"
                       : fmt::format("the other {} are kept in {} and a rerun with --resume "
                                     "computes only the missing ones",
                                     n - failed, folder.string()),
        failures));
  return records;
}

// ---- RankSession -----------------------------------------------------------------------------

RankSession::RankSession(int argc, char** argv) : args_(argv, argv + argc) {
  transport::start(&argc, &argv);
  const bool reproduce = args_.size() > 1 && args_[1] == "reproduce";
  bool has_out = false;
  if (transport::rank() != 0) {
    private_dir_ = (fs::temp_directory_path() /
                    fmt::format("implicit-rank{}-{}", transport::rank(), ::getpid()))
                       .string();
    fs::create_directories(private_dir_);
  }
  for (std::size_t k = 1; k < args_.size(); ++k) {
    std::string& a = args_[k];
    if (a == "--out" && k + 1 < args_.size()) {
      has_out = true;
      g_resume_root = args_[k + 1];
      if (!private_dir_.empty()) args_[k + 1] = private_dir_ + "/out";
    } else if (a.starts_with("--out=")) {
      has_out = true;
      g_resume_root = a.substr(6);
      if (!private_dir_.empty()) a = "--out=" + private_dir_ + "/out";
    }
  }
  if (reproduce && !has_out) {
    g_resume_root = "out";  // reproduce's default --out
    if (!private_dir_.empty()) args_.insert(args_.end(), {"--out", private_dir_ + "/out"});
  }
  if (!private_dir_.empty()) {
    // Only rank 0 speaks: the others compute the same and would repeat every line.
    std::fflush(stdout);
    std::fflush(stderr);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(null, STDERR_FILENO);
    ::close(null);
  }
  for (auto& a : args_) pointers_.push_back(a.data());
  pointers_.push_back(nullptr);
}

RankSession::~RankSession() {
  if (!private_dir_.empty()) {
    std::error_code ec;
    fs::remove_all(private_dir_, ec);
  }
  transport::stop();
}

int RankSession::finish(int code) {
  // Every rank computed the same thing, so all normally end with the same code at about the same
  // time. A rank that failed alone (a disk error on rank 0, say) would leave the others waiting
  // in a collective: after a minute without them the job is stopped with the failing code.
  return transport::agree_exit_code(code, 60.0);
}

int rank_index() { return transport::rank(); }
int rank_count() { return transport::size(); }

}  // namespace implicit::experiments
