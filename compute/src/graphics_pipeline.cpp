// Graphics pipelines from a PipelineState (see graphics_pipeline.h).
#include "hsi/compute/graphics_pipeline.h"

#include "hsi/compute/shader_module.h"

namespace hsi::compute {

GraphicsPipeline::GraphicsPipeline(const Context& context, const PipelineLayout& layout, const RenderPass& pass,
                                   std::span<const uint32_t> vertex_spirv, std::span<const uint32_t> fragment_spirv,
                                   const PipelineState& state) {
  const ShaderModule vs(context, vertex_spirv), fs(context, fragment_spirv);
  VkPipelineShaderStageCreateInfo stages[2] = {};
  stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vs.handle();
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = fs.handle();
  stages[1].pName = "main";

  VkPipelineVertexInputStateCreateInfo vi{};
  vi.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO;
  vi.vertexBindingDescriptionCount = static_cast<uint32_t>(state.vertex_input.bindings.size());
  vi.pVertexBindingDescriptions = state.vertex_input.bindings.data();
  vi.vertexAttributeDescriptionCount = static_cast<uint32_t>(state.vertex_input.attributes.size());
  vi.pVertexAttributeDescriptions = state.vertex_input.attributes.data();
  VkPipelineInputAssemblyStateCreateInfo ia{};
  ia.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO;
  ia.topology = state.topology;

  const bool fixed = state.viewport.width > 0 && state.viewport.height > 0;
  const VkViewport viewport{0, 0, static_cast<float>(state.viewport.width), static_cast<float>(state.viewport.height), 0, 1};
  const VkRect2D scissor{{0, 0}, state.viewport};
  VkPipelineViewportStateCreateInfo vp{};
  vp.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO;
  vp.viewportCount = 1;
  vp.pViewports = fixed ? &viewport : nullptr;
  vp.scissorCount = 1;
  vp.pScissors = fixed ? &scissor : nullptr;
  const VkDynamicState dynamic[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo ds{};
  ds.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO;
  ds.dynamicStateCount = 2;
  ds.pDynamicStates = dynamic;

  VkPipelineRasterizationStateCreateInfo rs{};
  rs.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO;
  rs.polygonMode = state.rasterization.polygon_mode;
  rs.cullMode = state.rasterization.cull_mode;
  rs.frontFace = state.rasterization.front_face;
  rs.lineWidth = 1;
  VkPipelineMultisampleStateCreateInfo ms{};
  ms.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO;
  ms.rasterizationSamples = state.samples;
  VkPipelineColorBlendAttachmentState blend{};
  blend.blendEnable = state.blend.enable ? VK_TRUE : VK_FALSE;
  blend.srcColorBlendFactor = state.blend.src_color;
  blend.dstColorBlendFactor = state.blend.dst_color;
  blend.colorBlendOp = VK_BLEND_OP_ADD;
  blend.srcAlphaBlendFactor = state.blend.src_alpha;
  blend.dstAlphaBlendFactor = state.blend.dst_alpha;
  blend.alphaBlendOp = VK_BLEND_OP_ADD;
  blend.colorWriteMask =
      VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo cb{};
  cb.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO;
  cb.attachmentCount = 1;
  cb.pAttachments = &blend;

  VkGraphicsPipelineCreateInfo gp{};
  gp.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO;
  gp.stageCount = 2;
  gp.pStages = stages;
  gp.pVertexInputState = &vi;
  gp.pInputAssemblyState = &ia;
  gp.pViewportState = &vp;
  gp.pRasterizationState = &rs;
  gp.pMultisampleState = &ms;
  gp.pColorBlendState = &cb;
  gp.pDynamicState = fixed ? nullptr : &ds;
  gp.layout = layout.handle();
  gp.renderPass = pass.handle();
  gp.subpass = 0;
  VkPipeline raw = VK_NULL_HANDLE;
  check(vkCreateGraphicsPipelines(context.device(), VK_NULL_HANDLE, 1, &gp, nullptr, &raw), "vkCreateGraphicsPipelines");
  pipeline_ = DeviceHandle<VkPipeline>(context.device(), raw, [](VkDevice d, VkPipeline p) { vkDestroyPipeline(d, p, nullptr); });
}

void GraphicsPipeline::bind(VkCommandBuffer cmd) const { vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_.get()); }

}  // namespace hsi::compute
