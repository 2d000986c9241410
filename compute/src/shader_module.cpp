// SPIR-V shader modules (see shader_module.h).
#include "hsi/compute/shader_module.h"

namespace hsi::compute {

ShaderModule::ShaderModule(const Context& context, std::span<const uint32_t> spirv) {
  VkShaderModuleCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
  info.codeSize = spirv.size_bytes();
  info.pCode = spirv.data();
  VkShaderModule raw = VK_NULL_HANDLE;
  check(vkCreateShaderModule(context.device(), &info, nullptr, &raw), "vkCreateShaderModule");
  module_ = DeviceHandle<VkShaderModule>(context.device(), raw,
                                         [](VkDevice d, VkShaderModule m) { vkDestroyShaderModule(d, m, nullptr); });
}

}  // namespace hsi::compute
