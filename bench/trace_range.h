// An NVTX range around a benchmark's phase, so that a GPU timeline (bench/cuda_trace)
// can find it: bench/cuda_trace/summarize.py sums the kernels, copies and waits inside
// each range. NVTX is header-only and costs a branch when no tool is attached; builds
// without CUDA compile it away.
#pragma once

#if defined(HSI_BENCH_NVTX)
#include <nvtx3/nvToolsExt.h>
#endif

#include <string>

namespace hsi::bench {

class TraceRange {
 public:
  explicit TraceRange([[maybe_unused]] const std::string& name) {
#if defined(HSI_BENCH_NVTX)
    nvtxRangePushA(name.c_str());
#endif
  }
  ~TraceRange() {
#if defined(HSI_BENCH_NVTX)
    nvtxRangePop();
#endif
  }
  TraceRange(const TraceRange&) = delete;
  TraceRange& operator=(const TraceRange&) = delete;
};

}  // namespace hsi::bench
