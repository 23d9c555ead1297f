#pragma once
// wilson95 of the experiments layer (experiments/wilson.hpp), by its name here.
#include "experiments/wilson.hpp"

namespace implicit::app {
using experiments::wilson95;
}  // namespace implicit::app
