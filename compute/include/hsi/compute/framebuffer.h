// The images a render pass draws into (its attachments' views, in order).
#pragma once

#include <span>

#include "hsi/compute/render_pass.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class Framebuffer {
 public:
  Framebuffer() = default;
  Framebuffer(const Context& context, const RenderPass& pass, std::span<const VkImageView> attachments, VkExtent2D extent);

  VkFramebuffer handle() const { return framebuffer_.get(); }
  VkExtent2D extent() const { return extent_; }

 private:
  DeviceHandle<VkFramebuffer> framebuffer_;
  VkExtent2D extent_{0, 0};
};

}  // namespace hsi::compute
