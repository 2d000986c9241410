// A compute pipeline whose descriptor set 0 has one binding per entry of `bindings`
// (binding i has type bindings[i]), with an optional push-constant range of
// push_constant_bytes at offset 0.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "hsi/compute/descriptor_set.h"
#include "hsi/compute/pipeline_layout.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class ComputePipeline {
 public:
  ComputePipeline() = default;
  ComputePipeline(const Context& context, std::span<const uint32_t> spirv,
                  std::span<const VkDescriptorType> bindings, uint32_t push_constant_bytes = 0);

  VkPipeline pipeline() const { return pipeline_.get(); }
  const PipelineLayout& layout() const { return layout_; }

  // Records binding this pipeline with `set` as its set 0, for the dispatches after.
  void bind(VkCommandBuffer cmd, const DescriptorSet& set) const;
  // Records pushing `bytes` of push constants at offset 0.
  void push(VkCommandBuffer cmd, const void* data, uint32_t bytes) const { layout_.push(cmd, data, bytes); }

 private:
  PipelineLayout layout_;
  DeviceHandle<VkPipeline> pipeline_;
};

}  // namespace hsi::compute
