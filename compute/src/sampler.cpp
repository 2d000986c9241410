// Samplers (see sampler.h).
#include "hsi/compute/sampler.h"

namespace hsi::compute {

Sampler::Sampler(const Context& context, const SamplerInfo& info) {
  VkSamplerCreateInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
  si.magFilter = info.filter;
  si.minFilter = info.filter;
  si.mipmapMode = info.mipmap;
  si.addressModeU = si.addressModeV = si.addressModeW = info.address;
  si.maxLod = info.max_lod;
  VkSampler raw = VK_NULL_HANDLE;
  check(vkCreateSampler(context.device(), &si, nullptr, &raw), "vkCreateSampler");
  sampler_ = DeviceHandle<VkSampler>(context.device(), raw, [](VkDevice d, VkSampler s) { vkDestroySampler(d, s, nullptr); });
}

}  // namespace hsi::compute
