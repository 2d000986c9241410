// Device diagnostics: how much arithmetic compute work on a context's queue reaches,
// to compare a pass's cost with the GPU's peak (on the H100 the graphics+compute
// queue reaches ~55 of ~67 TFLOP/s float: compute dispatches use the whole chip,
// although only two of its TPCs can draw). Used by bench_vulkan --probe.
#pragma once

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

struct ThroughputProbe {
  double gflops = 0;     // fused multiply-adds × 2 per second, by timestamps (wall time where none)
  double device_ms = 0;  // the timed dispatch
  uint64_t invocations = 0;
  bool double_precision = false;
};

// One warm-up and one timed dispatch of `workgroups` × 256 invocations, each running
// 8 independent FMA chains of `iterations` steps. Double needs shaderFloat64 (else
// VulkanError).
ThroughputProbe probe_fma_throughput(const Context& context, bool double_precision, uint32_t workgroups = 16384,
                                     uint32_t iterations = 4096);

}  // namespace hsi::compute
