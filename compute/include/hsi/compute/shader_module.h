// A SPIR-V shader module (the embedded shaders of compute/ and viewer/), kept for as
// long as the pipelines that are built from it need it.
#pragma once

#include <cstdint>
#include <span>

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class ShaderModule {
 public:
  ShaderModule() = default;
  ShaderModule(const Context& context, std::span<const uint32_t> spirv);

  VkShaderModule handle() const { return module_.get(); }

 private:
  DeviceHandle<VkShaderModule> module_;
};

}  // namespace hsi::compute
