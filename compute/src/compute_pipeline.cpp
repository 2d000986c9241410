// Compute pipelines (see compute_pipeline.h).
#include "hsi/compute/compute_pipeline.h"

#include "hsi/compute/shader_module.h"

namespace hsi::compute {

namespace {
std::vector<Binding> compute_bindings(std::span<const VkDescriptorType> types) {
  std::vector<Binding> b;
  for (VkDescriptorType t : types) b.push_back({t, VK_SHADER_STAGE_COMPUTE_BIT});
  return b;
}
}  // namespace

ComputePipeline::ComputePipeline(const Context& context, std::span<const uint32_t> spirv,
                                 std::span<const VkDescriptorType> bindings, uint32_t push_constant_bytes)
    : layout_(context, compute_bindings(bindings), VK_SHADER_STAGE_COMPUTE_BIT, push_constant_bytes) {
  const ShaderModule module(context, spirv);
  VkComputePipelineCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO;
  info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = module.handle();
  info.stage.pName = "main";
  info.layout = layout_.handle();
  VkPipeline pipeline = VK_NULL_HANDLE;
  check(vkCreateComputePipelines(context.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
        "vkCreateComputePipelines");
  pipeline_ = DeviceHandle<VkPipeline>(context.device(), pipeline,
                                       [](VkDevice d, VkPipeline p) { vkDestroyPipeline(d, p, nullptr); });
}

void ComputePipeline::bind(VkCommandBuffer cmd, const DescriptorSet& set) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.get());
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, set);
}

}  // namespace hsi::compute
