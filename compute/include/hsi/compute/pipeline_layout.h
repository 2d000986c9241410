// The layout of a pipeline: descriptor set 0 with one binding per entry (binding i
// has bindings[i]'s type, seen by its stages) and an optional push-constant range at
// offset 0. Compute and graphics pipelines and descriptor sets are made from it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class DescriptorSet;

struct Binding {
  VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  VkShaderStageFlags stages = VK_SHADER_STAGE_COMPUTE_BIT;
};

class PipelineLayout {
 public:
  PipelineLayout() = default;
  PipelineLayout(const Context& context, std::span<const Binding> bindings, VkShaderStageFlags push_stages = 0,
                 uint32_t push_constant_bytes = 0);

  VkPipelineLayout handle() const { return layout_.get(); }
  VkDescriptorSetLayout set_layout() const { return set_layout_.get(); }
  const std::vector<VkDescriptorType>& bindings() const { return types_; }

  // Records binding `set` as set 0 for the pipelines of `bind_point` bound after.
  void bind(VkCommandBuffer cmd, VkPipelineBindPoint bind_point, const DescriptorSet& set) const;
  // Records pushing `bytes` of push constants at offset 0 (to the layout's push stages).
  void push(VkCommandBuffer cmd, const void* data, uint32_t bytes) const;

 private:
  DeviceHandle<VkDescriptorSetLayout> set_layout_;
  DeviceHandle<VkPipelineLayout> layout_;
  std::vector<VkDescriptorType> types_;
  VkShaderStageFlags push_stages_ = 0;
};

}  // namespace hsi::compute
