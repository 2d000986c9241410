// One descriptor set for a pipeline layout's set 0, from its own small pool.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "hsi/compute/pipeline_layout.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class DescriptorSet {
 public:
  DescriptorSet() = default;
  DescriptorSet(const Context& context, const PipelineLayout& layout);
  DescriptorSet(DescriptorSet&& o) noexcept
      : context_(o.context_), bindings_(std::move(o.bindings_)), pool_(std::move(o.pool_)),
        set_(std::exchange(o.set_, VK_NULL_HANDLE)) {}
  DescriptorSet& operator=(DescriptorSet&& o) noexcept {
    if (this != &o) {
      context_ = o.context_;
      bindings_ = std::move(o.bindings_);
      pool_ = std::move(o.pool_);
      set_ = std::exchange(o.set_, VK_NULL_HANDLE);
    }
    return *this;
  }

  // Points binding `binding` at the whole buffer (its type is the layout's).
  void bind(uint32_t binding, const Buffer& buffer);
  // Points an image binding (combined image sampler: with `sampler`; storage image:
  // sampler ignored) at `view` in `layout`.
  void bind(uint32_t binding, VkImageView view, VkImageLayout layout, VkSampler sampler = VK_NULL_HANDLE);
  VkDescriptorSet handle() const { return set_; }

 private:
  void check_binding(uint32_t binding) const;
  const Context* context_ = nullptr;
  std::vector<VkDescriptorType> bindings_;
  DeviceHandle<VkDescriptorPool> pool_;  // owns set_
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

}  // namespace hsi::compute
