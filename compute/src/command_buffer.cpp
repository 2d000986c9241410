// Resettable command buffers (see command_buffer.h).
#include "hsi/compute/command_buffer.h"

namespace hsi::compute {

CommandBuffer::CommandBuffer(const Context& context) {
  const VkDevice dev = context.device();
  VkCommandPoolCreateInfo cp{};
  cp.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  cp.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  cp.queueFamilyIndex = context.queue_family();
  VkCommandPool pool = VK_NULL_HANDLE;
  check(vkCreateCommandPool(dev, &cp, nullptr, &pool), "vkCreateCommandPool");
  pool_ = DeviceHandle<VkCommandPool>(dev, pool, [](VkDevice d, VkCommandPool p) { vkDestroyCommandPool(d, p, nullptr); });
  VkCommandBufferAllocateInfo ca{};
  ca.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  ca.commandPool = pool;
  ca.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ca.commandBufferCount = 1;
  check(vkAllocateCommandBuffers(dev, &ca, &cmd_), "vkAllocateCommandBuffers");
}

void CommandBuffer::begin() const {
  check(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd_, &begin), "vkBeginCommandBuffer");
}

void CommandBuffer::end() const { check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer"); }

}  // namespace hsi::compute
