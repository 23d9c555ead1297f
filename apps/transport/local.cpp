// One process: the transport of the build without MPI.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "experiments/transport.hpp"

namespace implicit::experiments::transport {

// Started by mpirun or srun with several processes, a build without MPI would run the whole
// command in every process, each writing the same files: refuse, saying what to do instead.
bool start(int*, char***) {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}) {
    const char* value = std::getenv(name);
    if (value == nullptr || std::atoi(value) <= 1) continue;
    std::fprintf(stderr,
                 "implicit: started as one of %s processes of an MPI job (%s), but this build "
                 "has no MPI: every process would run the whole command. Build with "
                 "-DIMPLICIT_WITH_MPI=ON (docs/cluster.md), or run without the launcher.\n",
                 value, name);
    std::exit(2);
  }
  return false;
}
void stop() {}
void abort_job(int code) { std::exit(code); }
int rank() { return 0; }
int size() { return 1; }
int agree_exit_code(int code, double) { return code; }
std::string all_gather(const std::string& local) { return local; }
std::string broadcast(const std::string& data) { return data; }

struct SharedCounter::State {
  std::uint64_t value = 0;
};
SharedCounter::SharedCounter() : state_(std::make_unique<State>()) {}
SharedCounter::~SharedCounter() = default;
std::uint64_t SharedCounter::take(std::uint64_t k) {
  const std::uint64_t v = state_->value;
  state_->value += k;
  return v;
}

}  // namespace implicit::experiments::transport
