// Descriptor set layouts and pipeline layouts (see pipeline_layout.h).
#include "hsi/compute/pipeline_layout.h"

#include "hsi/compute/descriptor_set.h"

namespace hsi::compute {

PipelineLayout::PipelineLayout(const Context& context, std::span<const Binding> bindings, VkShaderStageFlags push_stages,
                               uint32_t push_constant_bytes)
    : push_stages_(push_stages) {
  const VkDevice dev = context.device();
  std::vector<VkDescriptorSetLayoutBinding> b(bindings.size());
  for (size_t i = 0; i < bindings.size(); ++i) {
    b[i].binding = static_cast<uint32_t>(i);
    b[i].descriptorType = bindings[i].type;
    b[i].descriptorCount = 1;
    b[i].stageFlags = bindings[i].stages;
    types_.push_back(bindings[i].type);
  }
  VkDescriptorSetLayoutCreateInfo set_info{};
  set_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  set_info.bindingCount = static_cast<uint32_t>(b.size());
  set_info.pBindings = b.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  check(vkCreateDescriptorSetLayout(dev, &set_info, nullptr, &set_layout), "vkCreateDescriptorSetLayout");
  set_layout_ = DeviceHandle<VkDescriptorSetLayout>(
      dev, set_layout, [](VkDevice d, VkDescriptorSetLayout l) { vkDestroyDescriptorSetLayout(d, l, nullptr); });

  const VkPushConstantRange push{push_stages, 0, push_constant_bytes};
  VkPipelineLayoutCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
  info.setLayoutCount = 1;
  info.pSetLayouts = &set_layout;
  info.pushConstantRangeCount = push_constant_bytes ? 1u : 0u;
  info.pPushConstantRanges = &push;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  check(vkCreatePipelineLayout(dev, &info, nullptr, &layout), "vkCreatePipelineLayout");
  layout_ = DeviceHandle<VkPipelineLayout>(dev, layout,
                                           [](VkDevice d, VkPipelineLayout l) { vkDestroyPipelineLayout(d, l, nullptr); });
}

void PipelineLayout::bind(VkCommandBuffer cmd, VkPipelineBindPoint bind_point, const DescriptorSet& set) const {
  const VkDescriptorSet s = set.handle();
  vkCmdBindDescriptorSets(cmd, bind_point, layout_.get(), 0, 1, &s, 0, nullptr);
}

void PipelineLayout::push(VkCommandBuffer cmd, const void* data, uint32_t bytes) const {
  vkCmdPushConstants(cmd, layout_.get(), push_stages_, 0, bytes, data);
}

}  // namespace hsi::compute
