// Milliseconds since a steady-clock time point: the one timing helper of the engine, the
// backends, compare/ and the benchmarks (each defined its own copy before).
#pragma once

#include <chrono>

namespace hsi {

inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace hsi
