// Device images and texture uploads (see image.h).
#include "hsi/compute/image.h"

#include <algorithm>

namespace hsi::compute {

uint32_t mip_levels(uint32_t width, uint32_t height) {
  uint32_t mips = 1;
  while ((std::max(width, height) >> mips) > 0) ++mips;
  return mips;
}

DeviceHandle<VkImageView> make_image_view(const Context& context, VkImage image, VkFormat format, uint32_t mips) {
  VkImageViewCreateInfo view{};
  view.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
  view.image = image;
  view.viewType = VK_IMAGE_VIEW_TYPE_2D;
  view.format = format;
  view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, mips, 0, 1};
  VkImageView raw = VK_NULL_HANDLE;
  check(vkCreateImageView(context.device(), &view, nullptr, &raw), "vkCreateImageView");
  return DeviceHandle<VkImageView>(context.device(), raw, [](VkDevice d, VkImageView v) { vkDestroyImageView(d, v, nullptr); });
}

Image::Image(const Context& context, const ImageInfo& info) : info_(info) {
  const VkDevice dev = context.device();
  VkImageCreateInfo ci{};
  ci.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
  ci.imageType = VK_IMAGE_TYPE_2D;
  ci.format = info.format;
  ci.extent = {info.width, info.height, 1};
  ci.mipLevels = info.mips;
  ci.arrayLayers = 1;
  ci.samples = info.samples;
  ci.tiling = VK_IMAGE_TILING_OPTIMAL;
  ci.usage = info.usage;
  ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage raw = VK_NULL_HANDLE;
  check(vkCreateImage(dev, &ci, nullptr, &raw), "vkCreateImage");
  image_ = DeviceHandle<VkImage>(dev, raw, [](VkDevice d, VkImage i) { vkDestroyImage(d, i, nullptr); });
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(dev, raw, &req);
  memory_ = allocate_memory(context, req, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | info.preferred_memory);
  check(vkBindImageMemory(dev, raw, memory_.get(), 0), "vkBindImageMemory");

  view_ = make_image_view(context, raw, info.format, info.mips);
}

Image& Image::operator=(Image&& o) noexcept {
  if (this != &o) {
    reset();  // view, image, then memory (member-wise assignment would free the memory first)
    info_ = o.info_;
    memory_ = std::move(o.memory_);
    image_ = std::move(o.image_);
    view_ = std::move(o.view_);
  }
  return *this;
}

void Image::reset() {
  view_.reset();
  image_.reset();
  memory_.reset();
}

void Image::record_upload(VkCommandBuffer cmd, const Buffer& staging, VkImageLayout from, VkPipelineStageFlags readers) const {
  const VkImage image = image_.get();
  const uint32_t mips = info_.mips;
  // A discarded image waits for nothing; one being sampled waits for its readers.
  const bool fresh = from == VK_IMAGE_LAYOUT_UNDEFINED;
  const VkAccessFlags before = fresh ? VkAccessFlags{0} : VkAccessFlags{VK_ACCESS_SHADER_READ_BIT};
  const VkPipelineStageFlags before_stages = fresh ? VkPipelineStageFlags{VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT} : readers;
  image_barrier(cmd, image, from, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, before, VK_ACCESS_TRANSFER_WRITE_BIT, before_stages,
                VK_PIPELINE_STAGE_TRANSFER_BIT, 0, mips);
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {info_.width, info_.height, 1};
  vkCmdCopyBufferToImage(cmd, staging.handle(), image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  int32_t mw = static_cast<int32_t>(info_.width), mh = static_cast<int32_t>(info_.height);
  for (uint32_t level = 1; level < mips; ++level) {
    image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                  VK_PIPELINE_STAGE_TRANSFER_BIT, level - 1, 1);
    const int32_t nw = std::max(1, mw / 2), nh = std::max(1, mh / 2);
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level - 1, 0, 1};
    blit.srcOffsets[1] = {mw, mh, 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, 0, 1};
    blit.dstOffsets[1] = {nw, nh, 1};
    vkCmdBlitImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit,
                   VK_FILTER_LINEAR);
    mw = nw;
    mh = nh;
  }
  if (mips > 1)
    image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                  VK_ACCESS_TRANSFER_READ_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, readers, 0,
                  mips - 1);
  image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, readers, mips - 1, 1);
}

}  // namespace hsi::compute
