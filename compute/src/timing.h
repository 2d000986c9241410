// Host wall-clock timing for the stats the passes report (private to compute/src).
#pragma once

#include "hsi/stopwatch.h"
#include <chrono>

namespace hsi::compute {

using Clock = std::chrono::steady_clock;

}  // namespace hsi::compute
