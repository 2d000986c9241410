// Fences and semaphores: one-shot submissions (Context::submit_and_wait) and the
// viewer's frames in flight.
#pragma once

#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

// A fence, created signaled when `signaled` (a frame slot that has nothing pending).
DeviceHandle<VkFence> make_fence(const Context& context, bool signaled = false);
DeviceHandle<VkSemaphore> make_semaphore(const Context& context);

}  // namespace hsi::compute
