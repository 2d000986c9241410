// Fences and semaphores (see sync.h).
#include "hsi/compute/sync.h"

namespace hsi::compute {

DeviceHandle<VkFence> make_fence(const Context& context, bool signaled) {
  VkFenceCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  info.flags = signaled ? VkFenceCreateFlags{VK_FENCE_CREATE_SIGNALED_BIT} : VkFenceCreateFlags{0};
  VkFence raw = VK_NULL_HANDLE;
  check(vkCreateFence(context.device(), &info, nullptr, &raw), "vkCreateFence");
  return DeviceHandle<VkFence>(context.device(), raw, [](VkDevice d, VkFence f) { vkDestroyFence(d, f, nullptr); });
}

DeviceHandle<VkSemaphore> make_semaphore(const Context& context) {
  VkSemaphoreCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
  VkSemaphore raw = VK_NULL_HANDLE;
  check(vkCreateSemaphore(context.device(), &info, nullptr, &raw), "vkCreateSemaphore");
  return DeviceHandle<VkSemaphore>(context.device(), raw, [](VkDevice d, VkSemaphore s) { vkDestroySemaphore(d, s, nullptr); });
}

}  // namespace hsi::compute
