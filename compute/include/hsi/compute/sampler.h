// A texture sampler, described by a value with defaults (bilinear, trilinear across
// mip levels, clamped to the edge).
#pragma once

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

struct SamplerInfo {
  VkFilter filter = VK_FILTER_LINEAR;  // magnification and minification
  VkSamplerMipmapMode mipmap = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  VkSamplerAddressMode address = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  float max_lod = VK_LOD_CLAMP_NONE;  // 0: level 0 only
};

class Sampler {
 public:
  Sampler() = default;
  Sampler(const Context& context, const SamplerInfo& info = {});

  VkSampler handle() const { return sampler_.get(); }

 private:
  DeviceHandle<VkSampler> sampler_;
};

}  // namespace hsi::compute
