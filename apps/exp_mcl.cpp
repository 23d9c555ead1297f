// Placeholder until the experiment lands: fails with a clear message.
#include <stdexcept>

#include "experiments.hpp"

namespace implicit::app {
nlohmann::json run_mcl(const MclSettings&, const RunContext&) {
  throw std::runtime_error("experiment 'mcl' is not implemented yet");
}
}  // namespace implicit::app
