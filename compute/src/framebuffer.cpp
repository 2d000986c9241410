// Framebuffers (see framebuffer.h).
#include "hsi/compute/framebuffer.h"

namespace hsi::compute {

Framebuffer::Framebuffer(const Context& context, const RenderPass& pass, std::span<const VkImageView> attachments,
                         VkExtent2D extent)
    : extent_(extent) {
  VkFramebufferCreateInfo fb{};
  fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
  fb.renderPass = pass.handle();
  fb.attachmentCount = static_cast<uint32_t>(attachments.size());
  fb.pAttachments = attachments.data();
  fb.width = extent.width;
  fb.height = extent.height;
  fb.layers = 1;
  VkFramebuffer raw = VK_NULL_HANDLE;
  check(vkCreateFramebuffer(context.device(), &fb, nullptr, &raw), "vkCreateFramebuffer");
  framebuffer_ = DeviceHandle<VkFramebuffer>(context.device(), raw,
                                             [](VkDevice d, VkFramebuffer f) { vkDestroyFramebuffer(d, f, nullptr); });
}

}  // namespace hsi::compute
