// A primary command buffer from its own pool on the context's queue family, reset
// and re-recorded each time it is used (the viewer's frames in flight; one-shot work
// goes through Context::submit_and_wait).
#pragma once

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class CommandBuffer {
 public:
  CommandBuffer() = default;
  explicit CommandBuffer(const Context& context);

  VkCommandBuffer handle() const { return cmd_; }
  // Resets the buffer and begins recording it for one submission.
  void begin() const;
  void end() const;

 private:
  DeviceHandle<VkCommandPool> pool_;  // owns cmd_
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
};

}  // namespace hsi::compute
