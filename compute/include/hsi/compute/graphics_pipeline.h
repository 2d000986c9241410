// A graphics pipeline: a vertex and a fragment shader over a PipelineLayout, for
// subpass 0 of a RenderPass, with the fixed-function state of a PipelineState.
#pragma once

#include <cstdint>
#include <span>

#include "hsi/compute/pipeline_layout.h"
#include "hsi/compute/pipeline_state.h"
#include "hsi/compute/render_pass.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class GraphicsPipeline {
 public:
  GraphicsPipeline() = default;
  GraphicsPipeline(const Context& context, const PipelineLayout& layout, const RenderPass& pass,
                   std::span<const uint32_t> vertex_spirv, std::span<const uint32_t> fragment_spirv,
                   const PipelineState& state = {});

  VkPipeline handle() const { return pipeline_.get(); }
  explicit operator bool() const { return static_cast<bool>(pipeline_); }
  // Records binding the pipeline for the draws after.
  void bind(VkCommandBuffer cmd) const;

 private:
  DeviceHandle<VkPipeline> pipeline_;
};

}  // namespace hsi::compute
