// The GPU's clocks, for reports that time work on it (hsi compare, bench_cuda): GPU
// clocks drop while it idles, so a time means little without the clock it ran at.
#pragma once

#include <string>

namespace hsi::cuda {

struct Clocks {
  std::string device;                        // name of the current CUDA device
  bool nvml = false;                         // the current clocks, read by NVML
  int sm_mhz = 0, sm_max_mhz = 0, memory_mhz = 0;  // 0: unknown
  // Without NVML: sm_max_mhz and memory_mhz are the device's peak clocks
  // (cudaDevAttrClockRate, cudaDevAttrMemoryClockRate), sm_mhz is 0, and this says why.
  std::string why_not_nvml;
  // One line: "NVIDIA H100 80GB HBM3: SM 1980 MHz (max 1980 MHz), memory 2619 MHz (NVML, now)".
  std::string describe() const;
};

// The clocks of the current CUDA device now. NVML (the driver's libnvidia-ml.so.1) is
// loaded at run time, so nothing needs it where there is no driver. Throws Error where
// no CUDA device can be queried.
Clocks clocks();

}  // namespace hsi::cuda
