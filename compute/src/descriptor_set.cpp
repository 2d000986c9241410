// Descriptor sets, each from its own pool (see descriptor_set.h).
#include "hsi/compute/descriptor_set.h"

#include <algorithm>
#include <string>

namespace hsi::compute {

DescriptorSet::DescriptorSet(const Context& context, const PipelineLayout& layout)
    : context_(&context), bindings_(layout.bindings()) {
  const VkDevice dev = context.device();
  std::vector<VkDescriptorPoolSize> sizes;
  for (VkDescriptorType t : bindings_) {
    auto it = std::find_if(sizes.begin(), sizes.end(), [t](const VkDescriptorPoolSize& s) { return s.type == t; });
    if (it == sizes.end()) sizes.push_back({t, 1});
    else ++it->descriptorCount;
  }
  VkDescriptorPoolCreateInfo pool_info{};
  pool_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
  pool_info.maxSets = 1;
  pool_info.poolSizeCount = static_cast<uint32_t>(sizes.size());
  pool_info.pPoolSizes = sizes.data();
  VkDescriptorPool pool = VK_NULL_HANDLE;
  check(vkCreateDescriptorPool(dev, &pool_info, nullptr, &pool), "vkCreateDescriptorPool");
  pool_ = DeviceHandle<VkDescriptorPool>(dev, pool,
                                         [](VkDevice d, VkDescriptorPool p) { vkDestroyDescriptorPool(d, p, nullptr); });
  const VkDescriptorSetLayout set_layout = layout.set_layout();
  VkDescriptorSetAllocateInfo alloc{};
  alloc.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
  alloc.descriptorPool = pool;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &set_layout;
  check(vkAllocateDescriptorSets(dev, &alloc, &set_), "vkAllocateDescriptorSets");
}

void DescriptorSet::check_binding(uint32_t binding) const {
  if (binding >= bindings_.size())
    throw VulkanError("DescriptorSet::bind: binding " + std::to_string(binding) + " does not exist (the set has " +
                      std::to_string(bindings_.size()) + ")");
}

void DescriptorSet::bind(uint32_t binding, VkImageView view, VkImageLayout layout, VkSampler sampler) {
  check_binding(binding);
  const VkDescriptorType type = bindings_[binding];
  if (type != VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER && type != VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
    throw VulkanError("DescriptorSet::bind: binding " + std::to_string(binding) + " is not an image binding");
  VkDescriptorImageInfo info{type == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER ? sampler : VK_NULL_HANDLE, view, layout};
  VkWriteDescriptorSet w{};
  w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
  w.dstSet = set_;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = type;
  w.pImageInfo = &info;
  vkUpdateDescriptorSets(context_->device(), 1, &w, 0, nullptr);
}

void DescriptorSet::bind(uint32_t binding, const Buffer& buffer) {
  check_binding(binding);
  VkDescriptorBufferInfo info{buffer.handle(), 0, VK_WHOLE_SIZE};
  VkWriteDescriptorSet w{};
  w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
  w.dstSet = set_;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = bindings_[binding];
  w.pBufferInfo = &info;
  vkUpdateDescriptorSets(context_->device(), 1, &w, 0, nullptr);
}

}  // namespace hsi::compute
