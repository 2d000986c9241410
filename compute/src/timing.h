// Host wall-clock timing for the stats the passes report (private to compute/src).
#pragma once

#include <chrono>

namespace hsi::compute {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace hsi::compute
