// The fixed-function state of a graphics pipeline as a value with defaults, as
// Vulkan-Samples' rendering/pipeline_state.h: triangles from no vertex buffer, no
// culling (a folded frame has flipped triangles: they are drawn too), one sample, no
// blending, viewport and scissor set per draw. A pipeline sets only what differs.
#pragma once

#include <vector>

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

struct VertexInputState {
  std::vector<VkVertexInputBindingDescription> bindings;
  std::vector<VkVertexInputAttributeDescription> attributes;
};

struct RasterizationState {
  VkPolygonMode polygon_mode = VK_POLYGON_MODE_FILL;
  VkCullModeFlags cull_mode = VK_CULL_MODE_NONE;
  VkFrontFace front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
};

// Blending of the one colour attachment: with `enable`, result = src × src_factor +
// dst × dst_factor (colour and alpha each); the defaults are premultiplied "over".
struct ColorBlendState {
  bool enable = false;
  VkBlendFactor src_color = VK_BLEND_FACTOR_ONE, dst_color = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  VkBlendFactor src_alpha = VK_BLEND_FACTOR_ONE, dst_alpha = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
};

struct PipelineState {
  VertexInputState vertex_input;
  VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  RasterizationState rasterization;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
  ColorBlendState blend;
  // Viewport and scissor fixed to [0, width] × [0, height]; 0 × 0: dynamic, set by
  // vkCmdSetViewport / vkCmdSetScissor before drawing.
  VkExtent2D viewport{0, 0};
};

}  // namespace hsi::compute
