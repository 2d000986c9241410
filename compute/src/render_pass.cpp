// Render passes (see render_pass.h).
#include "hsi/compute/render_pass.h"

#include <cstring>
#include <vector>

#include "hsi/compute/framebuffer.h"

namespace hsi::compute {

RenderPass::RenderPass(const Context& context, const RenderPassInfo& info) : info_(info) {
  std::vector<VkAttachmentDescription> attachments;
  VkAttachmentDescription color{};
  color.format = info.color.format;
  color.samples = info.color.samples;
  color.loadOp = info.color.load;
  color.storeOp = info.color.store;
  color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  color.initialLayout = info.color.initial_layout;
  color.finalLayout = info.color.final_layout;
  attachments.push_back(color);
  if (info.resolve) {
    VkAttachmentDescription resolve = color;
    resolve.samples = VK_SAMPLE_COUNT_1_BIT;
    resolve.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    resolve.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    resolve.finalLayout = info.resolve_final_layout;
    attachments.push_back(resolve);
  }
  const VkAttachmentReference color_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  const VkAttachmentReference resolve_ref{1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &color_ref;
  subpass.pResolveAttachments = info.resolve ? &resolve_ref : nullptr;
  VkSubpassDependency deps[2] = {};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = info.wait_stages;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].srcAccessMask = info.wait_access;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].dstStageMask = info.reader_stages;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstAccessMask = info.reader_access;
  VkRenderPassCreateInfo rp{};
  rp.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
  rp.attachmentCount = static_cast<uint32_t>(attachments.size());
  rp.pAttachments = attachments.data();
  rp.subpassCount = 1;
  rp.pSubpasses = &subpass;
  rp.dependencyCount = 2;
  rp.pDependencies = deps;
  VkRenderPass raw = VK_NULL_HANDLE;
  check(vkCreateRenderPass(context.device(), &rp, nullptr, &raw), "vkCreateRenderPass");
  pass_ = DeviceHandle<VkRenderPass>(context.device(), raw, [](VkDevice d, VkRenderPass p) { vkDestroyRenderPass(d, p, nullptr); });
}

void RenderPass::begin(VkCommandBuffer cmd, const Framebuffer& framebuffer, const std::array<float, 4>& clear) const {
  VkClearValue value{};
  std::memcpy(value.color.float32, clear.data(), sizeof(float) * 4);
  VkRenderPassBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
  begin.renderPass = pass_.get();
  begin.framebuffer = framebuffer.handle();
  begin.renderArea = {{0, 0}, framebuffer.extent()};
  begin.clearValueCount = 1;
  begin.pClearValues = &value;
  vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
}

}  // namespace hsi::compute
