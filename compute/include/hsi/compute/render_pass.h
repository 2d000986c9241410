// A single-subpass render pass with one colour attachment and, for MSAA, its resolve
// attachment, described by a value with defaults: a cleared RGBA8 image that is
// copied out afterwards. The two external dependencies say what must finish before
// the pass writes the attachment and who reads it after the pass.
#pragma once

#include <array>

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class Framebuffer;

struct ColorAttachment {
  VkFormat format = VK_FORMAT_R8G8B8A8_UNORM;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
  VkAttachmentLoadOp load = VK_ATTACHMENT_LOAD_OP_CLEAR;
  VkAttachmentStoreOp store = VK_ATTACHMENT_STORE_OP_STORE;
  VkImageLayout initial_layout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout final_layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
};

struct RenderPassInfo {
  ColorAttachment color;
  // A single-sample attachment 1 that the colour attachment resolves into (stored,
  // ending in resolve_final_layout).
  bool resolve = false;
  VkImageLayout resolve_final_layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  // Before the pass writes colour: these stages' work (and accesses) of earlier commands.
  VkPipelineStageFlags wait_stages = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  VkAccessFlags wait_access = 0;
  // After the pass: who reads what it wrote.
  VkPipelineStageFlags reader_stages = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkAccessFlags reader_access = VK_ACCESS_TRANSFER_READ_BIT;
};

class RenderPass {
 public:
  RenderPass() = default;
  RenderPass(const Context& context, const RenderPassInfo& info);

  VkRenderPass handle() const { return pass_.get(); }
  const RenderPassInfo& info() const { return info_; }
  explicit operator bool() const { return static_cast<bool>(pass_); }

  // Records beginning the pass on `framebuffer`, over all of it, clearing to `clear`
  // (used where the attachment is loaded with CLEAR).
  void begin(VkCommandBuffer cmd, const Framebuffer& framebuffer, const std::array<float, 4>& clear) const;

 private:
  RenderPassInfo info_;
  DeviceHandle<VkRenderPass> pass_;
};

}  // namespace hsi::compute
