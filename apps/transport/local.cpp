// One process: the transport of the build without MPI.
#include <cstdlib>

#include "transport.hpp"

namespace implicit::app::transport {

bool start(int*, char***) { return false; }
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

}  // namespace implicit::app::transport
