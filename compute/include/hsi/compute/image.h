// A 2D device image with its own memory and a view of all its mip levels (the
// renderer's targets and textures, the viewer's UI textures), and the upload of
// texels into it with its mip chain.
#pragma once

#include <cstdint>

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

struct ImageInfo {
  uint32_t width = 1, height = 1;
  VkFormat format = VK_FORMAT_R8G8B8A8_UNORM;
  VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
  uint32_t mips = 1;  // mip_levels(width, height) for a full chain
  // Memory flags wanted besides DEVICE_LOCAL (e.g. LAZILY_ALLOCATED for a transient
  // attachment); none is required.
  VkMemoryPropertyFlags preferred_memory = 0;
};

// Levels of a full mip chain down to 1 × 1.
uint32_t mip_levels(uint32_t width, uint32_t height);

// A 2D colour view of `image`'s first `mips` levels (an Image's own, or a swapchain
// image's, which the swapchain owns).
DeviceHandle<VkImageView> make_image_view(const Context& context, VkImage image, VkFormat format, uint32_t mips = 1);

class Image {
 public:
  Image() = default;
  Image(const Context& context, const ImageInfo& info);
  Image(Image&& o) noexcept = default;
  Image& operator=(Image&& o) noexcept;
  Image(const Image&) = delete;
  Image& operator=(const Image&) = delete;
  ~Image() { reset(); }

  VkImage handle() const { return image_.get(); }
  VkImageView view() const { return view_.get(); }
  const ImageInfo& info() const { return info_; }
  explicit operator bool() const { return static_cast<bool>(image_); }
  void reset();  // the view, the image, then its memory

  // Records the copy of `staging` (level 0's texels, tightly packed) into the image
  // and the other mip levels made from it by linear blits (the usage needs
  // TRANSFER_SRC when there are any); every level ends SHADER_READ_ONLY_OPTIMAL.
  // `from`: the layout the image is in (UNDEFINED: its contents are discarded; else
  // SHADER_READ_ONLY_OPTIMAL, read by `readers` before); `readers`: the shader
  // stages that sample it before and after.
  void record_upload(VkCommandBuffer cmd, const Buffer& staging, VkImageLayout from, VkPipelineStageFlags readers) const;

 private:
  ImageInfo info_;
  DeviceHandle<VkDeviceMemory> memory_;  // declared first: freed after the image and view
  DeviceHandle<VkImage> image_;
  DeviceHandle<VkImageView> view_;
};

}  // namespace hsi::compute
