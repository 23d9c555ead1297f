// Placeholder until the experiment lands: fails with a clear message.
#include <stdexcept>

#include "experiments.hpp"

namespace implicit::app {
nlohmann::json run_slit(const SlitSettings&, const RunContext&) {
  throw std::runtime_error("experiment 'slit' is not implemented yet");
}
}  // namespace implicit::app
