// MPI: the transport of the IMPLICIT_WITH_MPI build. MPI is started only under a launcher, so the
// same executable also runs as one ordinary process (no MPI start-up cost, no launcher needed).
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vector>

#include "experiments/transport.hpp"

namespace implicit::experiments::transport {
namespace {

bool g_active = false;

// Open MPI's mpirun, Slurm's srun (PMI-2 or PMIx) and MPICH's hydra set one of these.
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

void check(int status, const char* what) {
  if (status != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

int as_count(std::size_t n) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("MPI: more than 2 GiB of results from one rank");
  return static_cast<int>(n);
}

}  // namespace

bool start(int* argc, char*** argv) {
  if (!launched_by_mpi()) return false;
  // Only the main thread calls MPI; TBB's workers compute.
  int provided = 0;
  check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  g_active = true;
  return true;
}

void stop() {
  if (g_active) MPI_Finalize();
  g_active = false;
}

void abort_job(int code) {
  if (g_active) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

int rank() {
  int r = 0;
  if (g_active) MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int size() {
  int n = 1;
  if (g_active) MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

int agree_exit_code(int code, double timeout_seconds) {
  if (!g_active) return code;
  std::vector<int> codes(static_cast<std::size_t>(size()));
  MPI_Request request;
  check(MPI_Iallgather(&code, 1, MPI_INT, codes.data(), 1, MPI_INT, MPI_COMM_WORLD, &request),
        "MPI_Iallgather");
  const auto start = std::chrono::steady_clock::now();
  for (int done = 0; !done;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
        timeout_seconds)
      abort_job(code != 0 ? code : 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return *std::max_element(codes.begin(), codes.end());
}

std::string all_gather(const std::string& local) {
  if (!g_active) return local;
  const int n = size();
  const int mine = as_count(local.size());
  std::vector<int> counts(static_cast<std::size_t>(n)), offsets(static_cast<std::size_t>(n));
  check(MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD),
        "MPI_Allgather");
  std::size_t total = 0;
  for (int r = 0; r < n; ++r) {
    offsets[static_cast<std::size_t>(r)] = as_count(total);
    total += static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]);
  }
  as_count(total);
  std::string all(total, '\0');
  check(MPI_Allgatherv(local.data(), mine, MPI_BYTE, all.data(), counts.data(), offsets.data(),
                       MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Allgatherv");
  return all;
}

std::string broadcast(const std::string& data) {
  if (!g_active) return data;
  unsigned long long n = data.size();
  check(MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD), "MPI_Bcast");
  std::string out = rank() == 0 ? data : std::string(n, '\0');
  check(MPI_Bcast(out.data(), as_count(n), MPI_BYTE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  return out;
}

// The counter lives in rank 0's window; MPI_Fetch_and_op makes take() atomic across ranks
// without rank 0 having to answer (passive target).
struct SharedCounter::State {
  MPI_Win window = MPI_WIN_NULL;
  std::uint64_t* value = nullptr;
  std::uint64_t local = 0;
};

SharedCounter::SharedCounter() : state_(std::make_unique<State>()) {
  if (!g_active) return;
  const MPI_Aint bytes = rank() == 0 ? sizeof(std::uint64_t) : 0;
  check(MPI_Win_allocate(bytes, sizeof(std::uint64_t), MPI_INFO_NULL, MPI_COMM_WORLD,
                         &state_->value, &state_->window),
        "MPI_Win_allocate");
  if (rank() == 0) {
    MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, state_->window);
    *state_->value = 0;
    MPI_Win_unlock(0, state_->window);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

SharedCounter::~SharedCounter() {
  if (state_->window == MPI_WIN_NULL) return;
  MPI_Barrier(MPI_COMM_WORLD);  // nobody frees the window while another rank still takes
  MPI_Win_free(&state_->window);
}

std::uint64_t SharedCounter::take(std::uint64_t k) {
  if (state_->window == MPI_WIN_NULL) {
    const std::uint64_t v = state_->local;
    state_->local += k;
    return v;
  }
  std::uint64_t old = 0;
  MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, state_->window);
  MPI_Fetch_and_op(&k, &old, MPI_UINT64_T, 0, 0, MPI_SUM, state_->window);
  MPI_Win_unlock(0, state_->window);
  return old;
}

}  // namespace implicit::experiments::transport
