// See diagnostics.h.
#include "hsi/compute/diagnostics.h"

#include <array>
#include <chrono>

#include "hsi/compute/compute_pipeline.h"
#include "hsi/compute/spirv/probe_fma_f32.h"
#include "hsi/compute/spirv/probe_fma_f64.h"

namespace hsi::compute {

ThroughputProbe probe_fma_throughput(const Context& context, bool double_precision, uint32_t workgroups,
                                     uint32_t iterations) {
  if (double_precision && !context.info().float64)
    throw VulkanError("throughput probe: " + context.info().name + " has no shaderFloat64");
  constexpr uint32_t kLocal = 256;  // local_size_x of probe_fma.comp
  constexpr std::array<VkDescriptorType, 1> kBindings = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
  const std::span<const uint32_t> spirv =
      double_precision ? std::span<const uint32_t>(probe_fma_f64) : std::span<const uint32_t>(probe_fma_f32);
  ComputePipeline pipeline(context, spirv, kBindings, sizeof(uint32_t));
  DescriptorSet set(context, pipeline.layout());
  const uint64_t invocations = static_cast<uint64_t>(workgroups) * kLocal;
  Buffer out(context, invocations * (double_precision ? 8 : 4), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
             MemoryUse::kDeviceLocal);
  set.bind(0, out);
  const auto [gx, gy] = split_dispatch(context, workgroups);
  ThroughputProbe r;
  r.invocations = invocations;
  r.double_precision = double_precision;
  for (int pass = 0; pass < 2; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    context.submit_and_wait([&](VkCommandBuffer cmd) {
      pipeline.bind(cmd, set);
      pipeline.push(cmd, &iterations, sizeof(uint32_t));
      vkCmdDispatch(cmd, gx, gy, 1);
    });
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    r.device_ms = context.last_device_ms() > 0 ? context.last_device_ms() : wall;
  }
  r.gflops = static_cast<double>(invocations) * iterations * 8 * 2 / (r.device_ms * 1e-3) * 1e-9;
  return r;
}

}  // namespace hsi::compute
