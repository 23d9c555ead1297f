#pragma once
// counted(n, "run", "runs") of the experiments layer (experiments/plural.hpp), by its name here.
#include "experiments/plural.hpp"

namespace implicit::app {
using experiments::counted;
}  // namespace implicit::app
