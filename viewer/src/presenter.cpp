// Swapchain presentation and the ImGui renderer (see presenter.h).
#include "presenter.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "hsi/viewer/spirv/viewer_ui_frag.h"
#include "hsi/viewer/spirv/viewer_ui_vert.h"

namespace hsi::viewer {

namespace {

constexpr int kFramesInFlight = 2;

template <class T>
using Owned = vk::DeviceHandle<T>;

struct Texture {
  Owned<VkDeviceMemory> memory;
  Owned<VkImage> image;
  Owned<VkImageView> view;
  int width = 0, height = 0;
  void reset() {
    view.reset();
    image.reset();
    memory.reset();
    width = height = 0;
  }
};

Texture make_texture(const vk::Context& ctx, int w, int h) {
  const VkDevice dev = ctx.device();
  Texture t;
  VkImageCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = VK_FORMAT_R8G8B8A8_UNORM;
  info.extent = {static_cast<uint32_t>(w), static_cast<uint32_t>(h), 1};
  info.mipLevels = 1;
  info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage image = VK_NULL_HANDLE;
  vk::check(vkCreateImage(dev, &info, nullptr, &image), "vkCreateImage (viewer texture)");
  Owned<VkImage> owned_image(dev, image, [](VkDevice d, VkImage i) { vkDestroyImage(d, i, nullptr); });
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(dev, image, &req);
  VkMemoryAllocateInfo alloc{};
  alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = ctx.memory_type(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  VkDeviceMemory mem = VK_NULL_HANDLE;
  vk::check(vkAllocateMemory(dev, &alloc, nullptr, &mem), "vkAllocateMemory (viewer texture)");
  t.memory = Owned<VkDeviceMemory>(dev, mem, [](VkDevice d, VkDeviceMemory m) { vkFreeMemory(d, m, nullptr); });
  vk::check(vkBindImageMemory(dev, image, mem, 0), "vkBindImageMemory");
  t.image = std::move(owned_image);
  VkImageViewCreateInfo view{};
  view.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
  view.image = image;
  view.viewType = VK_IMAGE_VIEW_TYPE_2D;
  view.format = VK_FORMAT_R8G8B8A8_UNORM;
  view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VkImageView v = VK_NULL_HANDLE;
  vk::check(vkCreateImageView(dev, &view, nullptr, &v), "vkCreateImageView (viewer texture)");
  t.view = Owned<VkImageView>(dev, v, [](VkDevice d, VkImageView x) { vkDestroyImageView(d, x, nullptr); });
  t.width = w;
  t.height = h;
  return t;
}

// Records the copy of `staging` into `tex` (whole image), from `from` to shader-read.
void record_upload(VkCommandBuffer cmd, const vk::Buffer& staging, const Texture& tex, VkImageLayout from) {
  vk::image_barrier(cmd, tex.image.get(), from, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_ACCESS_SHADER_READ_BIT,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {static_cast<uint32_t>(tex.width), static_cast<uint32_t>(tex.height), 1};
  vkCmdCopyBufferToImage(cmd, staging.handle(), tex.image.get(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  vk::image_barrier(cmd, tex.image.get(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT);
}

Owned<VkShaderModule> shader(VkDevice dev, const uint32_t* code, size_t bytes) {
  VkShaderModuleCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
  info.codeSize = bytes;
  info.pCode = code;
  VkShaderModule m = VK_NULL_HANDLE;
  vk::check(vkCreateShaderModule(dev, &info, nullptr, &m), "vkCreateShaderModule (viewer)");
  return Owned<VkShaderModule>(dev, m, [](VkDevice d, VkShaderModule s) { vkDestroyShaderModule(d, s, nullptr); });
}

}  // namespace

struct Presenter::Impl {
  const vk::Context& ctx;
  GLFWwindow* window;
  bool vsync;
  VkDevice dev;

  // Swapchain and what depends on it.
  VkSwapchainKHR swapchain = VK_NULL_HANDLE;
  VkSurfaceFormatKHR format{};
  VkExtent2D extent{0, 0};
  bool can_capture = false;
  std::vector<VkImage> images;
  std::vector<Owned<VkImageView>> views;
  std::vector<Owned<VkFramebuffer>> framebuffers;
  std::vector<Owned<VkSemaphore>> rendered;  // per swapchain image: drawing done, present may start
  Owned<VkRenderPass> render_pass;
  Owned<VkPipeline> pipeline;

  // Fixed objects.
  Owned<VkSampler> sampler;
  Owned<VkDescriptorSetLayout> set_layout;
  Owned<VkPipelineLayout> layout;
  Owned<VkDescriptorPool> pool;
  VkDescriptorSet font_set = VK_NULL_HANDLE, frame_set = VK_NULL_HANDLE;
  Texture font, frame, blank;

  struct Frame {
    Owned<VkCommandPool> pool;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    Owned<VkFence> fence;
    Owned<VkSemaphore> acquired;
    vk::Buffer vertices, indices, staging;
    vk::Buffer readback;
  };
  std::array<Frame, kFramesInFlight> frames;
  int frame_index = 0;

  // A frame image waiting for upload.
  vk::RgbaImage pending;
  bool has_pending = false;
  bool frame_initialized = false;

  Impl(const vk::Context& c, GLFWwindow* w, bool v) : ctx(c), window(w), vsync(v), dev(c.device()) {}

  ~Impl() {
    if (dev) vkDeviceWaitIdle(dev);
    destroy_swapchain();
  }

  void destroy_swapchain() {
    framebuffers.clear();
    views.clear();
    rendered.clear();
    if (swapchain) vkDestroySwapchainKHR(dev, swapchain, nullptr);
    swapchain = VK_NULL_HANDLE;
  }

  void create_fixed();
  void create_swapchain();
  void create_pipeline();
  void write_set(VkDescriptorSet set, const Texture& tex);
  void ensure(vk::Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage, vk::MemoryUse use) {
    if (b && b.size() >= bytes) return;
    b = vk::Buffer(ctx, std::max<VkDeviceSize>(bytes + bytes / 2, 4096), usage, use);
  }
  void record_draw(VkCommandBuffer cmd, ImDrawData* data, Frame& f);
};

void Presenter::Impl::create_fixed() {
  VkSamplerCreateInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
  si.magFilter = VK_FILTER_LINEAR;
  si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  si.maxLod = 0;
  VkSampler s = VK_NULL_HANDLE;
  vk::check(vkCreateSampler(dev, &si, nullptr, &s), "vkCreateSampler (viewer)");
  sampler = Owned<VkSampler>(dev, s, [](VkDevice d, VkSampler x) { vkDestroySampler(d, x, nullptr); });

  const VkDescriptorSetLayoutBinding binding{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT,
                                             nullptr};
  VkDescriptorSetLayoutCreateInfo sl{};
  sl.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  sl.bindingCount = 1;
  sl.pBindings = &binding;
  VkDescriptorSetLayout l = VK_NULL_HANDLE;
  vk::check(vkCreateDescriptorSetLayout(dev, &sl, nullptr, &l), "vkCreateDescriptorSetLayout (viewer)");
  set_layout = Owned<VkDescriptorSetLayout>(dev, l, [](VkDevice d, VkDescriptorSetLayout x) { vkDestroyDescriptorSetLayout(d, x, nullptr); });

  const VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT, 0, 4 * sizeof(float)};
  VkPipelineLayoutCreateInfo li{};
  li.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
  li.setLayoutCount = 1;
  li.pSetLayouts = &l;
  li.pushConstantRangeCount = 1;
  li.pPushConstantRanges = &push;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  vk::check(vkCreatePipelineLayout(dev, &li, nullptr, &pl), "vkCreatePipelineLayout (viewer)");
  layout = Owned<VkPipelineLayout>(dev, pl, [](VkDevice d, VkPipelineLayout x) { vkDestroyPipelineLayout(d, x, nullptr); });

  const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 2};
  VkDescriptorPoolCreateInfo pi{};
  pi.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
  pi.maxSets = 2;
  pi.poolSizeCount = 1;
  pi.pPoolSizes = &size;
  VkDescriptorPool p = VK_NULL_HANDLE;
  vk::check(vkCreateDescriptorPool(dev, &pi, nullptr, &p), "vkCreateDescriptorPool (viewer)");
  pool = Owned<VkDescriptorPool>(dev, p, [](VkDevice d, VkDescriptorPool x) { vkDestroyDescriptorPool(d, x, nullptr); });
  const VkDescriptorSetLayout layouts[2] = {l, l};
  VkDescriptorSetAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
  ai.descriptorPool = p;
  ai.descriptorSetCount = 2;
  ai.pSetLayouts = layouts;
  VkDescriptorSet sets[2];
  vk::check(vkAllocateDescriptorSets(dev, &ai, sets), "vkAllocateDescriptorSets (viewer)");
  font_set = sets[0];
  frame_set = sets[1];

  for (Frame& f : frames) {
    VkCommandPoolCreateInfo cp{};
    cp.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
    cp.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cp.queueFamilyIndex = ctx.queue_family();
    VkCommandPool cpool = VK_NULL_HANDLE;
    vk::check(vkCreateCommandPool(dev, &cp, nullptr, &cpool), "vkCreateCommandPool (viewer)");
    f.pool = Owned<VkCommandPool>(dev, cpool, [](VkDevice d, VkCommandPool x) { vkDestroyCommandPool(d, x, nullptr); });
    VkCommandBufferAllocateInfo ca{};
    ca.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    ca.commandPool = cpool;
    ca.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ca.commandBufferCount = 1;
    vk::check(vkAllocateCommandBuffers(dev, &ca, &f.cmd), "vkAllocateCommandBuffers (viewer)");
    VkFenceCreateInfo fi{};
    fi.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
    fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    VkFence fence = VK_NULL_HANDLE;
    vk::check(vkCreateFence(dev, &fi, nullptr, &fence), "vkCreateFence (viewer)");
    f.fence = Owned<VkFence>(dev, fence, [](VkDevice d, VkFence x) { vkDestroyFence(d, x, nullptr); });
    VkSemaphoreCreateInfo sem{};
    sem.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
    VkSemaphore s2 = VK_NULL_HANDLE;
    vk::check(vkCreateSemaphore(dev, &sem, nullptr, &s2), "vkCreateSemaphore (viewer)");
    f.acquired = Owned<VkSemaphore>(dev, s2, [](VkDevice d, VkSemaphore x) { vkDestroySemaphore(d, x, nullptr); });
  }

  // Until the first frame arrives, the frame set shows a 1 × 1 white texture.
  blank = make_texture(ctx, 1, 1);
  vk::Buffer staging(ctx, 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::kUpload);
  const uint8_t white[4] = {255, 255, 255, 255};
  staging.write(white, 4);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) { record_upload(cmd, staging, blank, VK_IMAGE_LAYOUT_UNDEFINED); });
  write_set(frame_set, blank);
  write_set(font_set, blank);
}

void Presenter::Impl::write_set(VkDescriptorSet set, const Texture& tex) {
  const VkDescriptorImageInfo info{sampler.get(), tex.view.get(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet w{};
  w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
  w.dstSet = set;
  w.dstBinding = 0;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w.pImageInfo = &info;
  vkUpdateDescriptorSets(dev, 1, &w, 0, nullptr);
}

void Presenter::Impl::create_swapchain() {
  const VkPhysicalDevice phys = ctx.physical_device();
  const VkSurfaceKHR surface = ctx.surface();
  VkSurfaceCapabilitiesKHR caps;
  vk::check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(phys, surface, &caps), "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window, &fw, &fh);
  VkExtent2D want = caps.currentExtent;
  if (want.width == UINT32_MAX) want = {static_cast<uint32_t>(std::max(fw, 0)), static_cast<uint32_t>(std::max(fh, 0))};
  want.width = std::clamp(want.width, caps.minImageExtent.width, caps.maxImageExtent.width);
  want.height = std::clamp(want.height, caps.minImageExtent.height, caps.maxImageExtent.height);
  if (want.width == 0 || want.height == 0) {  // minimised: nothing to present to
    extent = {0, 0};
    return;
  }

  if (!swapchain || format.format == VK_FORMAT_UNDEFINED) {
    uint32_t n = 0;
    vk::check(vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &n, nullptr), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    std::vector<VkSurfaceFormatKHR> formats(n);
    vk::check(vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &n, formats.data()), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    if (formats.empty()) throw vk::VulkanError("viewer: the window's surface offers no formats");
    // UNORM: the rendered frame's bytes are already sRGB-encoded, as are ImGui's colours.
    format = formats[0];
    for (VkFormat f : {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM})
      for (const VkSurfaceFormatKHR& s : formats)
        if (s.format == f && s.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR && format.format != VK_FORMAT_B8G8R8A8_UNORM &&
            format.format != VK_FORMAT_R8G8B8A8_UNORM)
          format = s;
  }
  VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;  // always available
  if (!vsync) {
    uint32_t n = 0;
    vk::check(vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &n, nullptr), "vkGetPhysicalDeviceSurfacePresentModesKHR");
    std::vector<VkPresentModeKHR> modes(n);
    vk::check(vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &n, modes.data()), "vkGetPhysicalDeviceSurfacePresentModesKHR");
    for (VkPresentModeKHR m : {VK_PRESENT_MODE_MAILBOX_KHR, VK_PRESENT_MODE_IMMEDIATE_KHR})
      if (mode == VK_PRESENT_MODE_FIFO_KHR && std::find(modes.begin(), modes.end(), m) != modes.end()) mode = m;
  }
  uint32_t count = std::max(caps.minImageCount + 1, 3u);
  if (caps.maxImageCount > 0) count = std::min(count, caps.maxImageCount);
  can_capture = (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT) != 0;

  VkSwapchainCreateInfoKHR info{};
  info.sType = VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR;
  info.surface = surface;
  info.minImageCount = count;
  info.imageFormat = format.format;
  info.imageColorSpace = format.colorSpace;
  info.imageExtent = want;
  info.imageArrayLayers = 1;
  info.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | (can_capture ? VK_IMAGE_USAGE_TRANSFER_SRC_BIT : 0);
  info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.preTransform = (caps.supportedTransforms & VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR) ? VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR
                                                                                        : caps.currentTransform;
  info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  for (VkCompositeAlphaFlagBitsKHR a : {VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR, VK_COMPOSITE_ALPHA_INHERIT_BIT_KHR,
                                        VK_COMPOSITE_ALPHA_PRE_MULTIPLIED_BIT_KHR, VK_COMPOSITE_ALPHA_POST_MULTIPLIED_BIT_KHR})
    if (caps.supportedCompositeAlpha & a) {
      info.compositeAlpha = a;
      break;
    }
  info.presentMode = mode;
  info.clipped = VK_TRUE;
  const VkSwapchainKHR old = swapchain;
  info.oldSwapchain = old;
  VkSwapchainKHR sc = VK_NULL_HANDLE;
  vk::check(vkCreateSwapchainKHR(dev, &info, nullptr, &sc), "vkCreateSwapchainKHR");
  destroy_swapchain();  // the old one (after the new one took over its images' presentation)
  swapchain = sc;
  extent = want;

  uint32_t n = 0;
  vk::check(vkGetSwapchainImagesKHR(dev, swapchain, &n, nullptr), "vkGetSwapchainImagesKHR");
  images.resize(n);
  vk::check(vkGetSwapchainImagesKHR(dev, swapchain, &n, images.data()), "vkGetSwapchainImagesKHR");

  if (!render_pass) {
    VkAttachmentDescription color{};
    color.format = format.format;
    color.samples = VK_SAMPLE_COUNT_1_BIT;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    color.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    color.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
    const VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub{};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &ref;
    VkSubpassDependency deps[2] = {};
    // The acquire semaphore's wait is at colour output: the layout transition waits for it.
    deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    deps[0].dstSubpass = 0;
    deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    deps[0].srcAccessMask = 0;
    deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
    // Drawn before a capture copies the image.
    deps[1].srcSubpass = 0;
    deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
    deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    VkRenderPassCreateInfo rp{};
    rp.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
    rp.attachmentCount = 1;
    rp.pAttachments = &color;
    rp.subpassCount = 1;
    rp.pSubpasses = &sub;
    rp.dependencyCount = 2;
    rp.pDependencies = deps;
    VkRenderPass r = VK_NULL_HANDLE;
    vk::check(vkCreateRenderPass(dev, &rp, nullptr, &r), "vkCreateRenderPass (viewer)");
    render_pass = Owned<VkRenderPass>(dev, r, [](VkDevice d, VkRenderPass x) { vkDestroyRenderPass(d, x, nullptr); });
    create_pipeline();
  }

  for (VkImage image : images) {
    VkImageViewCreateInfo vi{};
    vi.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
    vi.image = image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format.format;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView v = VK_NULL_HANDLE;
    vk::check(vkCreateImageView(dev, &vi, nullptr, &v), "vkCreateImageView (swapchain)");
    views.emplace_back(dev, v, [](VkDevice d, VkImageView x) { vkDestroyImageView(d, x, nullptr); });
    VkFramebufferCreateInfo fb{};
    fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
    fb.renderPass = render_pass.get();
    fb.attachmentCount = 1;
    fb.pAttachments = &v;
    fb.width = extent.width;
    fb.height = extent.height;
    fb.layers = 1;
    VkFramebuffer f = VK_NULL_HANDLE;
    vk::check(vkCreateFramebuffer(dev, &fb, nullptr, &f), "vkCreateFramebuffer (swapchain)");
    framebuffers.emplace_back(dev, f, [](VkDevice d, VkFramebuffer x) { vkDestroyFramebuffer(d, x, nullptr); });
    VkSemaphoreCreateInfo sem{};
    sem.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
    VkSemaphore s = VK_NULL_HANDLE;
    vk::check(vkCreateSemaphore(dev, &sem, nullptr, &s), "vkCreateSemaphore (viewer)");
    rendered.emplace_back(dev, s, [](VkDevice d, VkSemaphore x) { vkDestroySemaphore(d, x, nullptr); });
  }
}

void Presenter::Impl::create_pipeline() {
  const Owned<VkShaderModule> vs = shader(dev, viewer_ui_vert, sizeof viewer_ui_vert);
  const Owned<VkShaderModule> fs = shader(dev, viewer_ui_frag, sizeof viewer_ui_frag);
  VkPipelineShaderStageCreateInfo stages[2] = {};
  stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vs.get();
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = fs.get();
  stages[1].pName = "main";
  const VkVertexInputBindingDescription vb{0, sizeof(ImDrawVert), VK_VERTEX_INPUT_RATE_VERTEX};
  const VkVertexInputAttributeDescription va[3] = {
      {0, 0, VK_FORMAT_R32G32_SFLOAT, static_cast<uint32_t>(offsetof(ImDrawVert, pos))},
      {1, 0, VK_FORMAT_R32G32_SFLOAT, static_cast<uint32_t>(offsetof(ImDrawVert, uv))},
      {2, 0, VK_FORMAT_R8G8B8A8_UNORM, static_cast<uint32_t>(offsetof(ImDrawVert, col))}};
  VkPipelineVertexInputStateCreateInfo vi{};
  vi.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO;
  vi.vertexBindingDescriptionCount = 1;
  vi.pVertexBindingDescriptions = &vb;
  vi.vertexAttributeDescriptionCount = 3;
  vi.pVertexAttributeDescriptions = va;
  VkPipelineInputAssemblyStateCreateInfo ia{};
  ia.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO;
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{};
  vp.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO;
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{};
  rs.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO;
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  rs.cullMode = VK_CULL_MODE_NONE;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1;
  VkPipelineMultisampleStateCreateInfo ms{};
  ms.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO;
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineColorBlendAttachmentState blend{};
  blend.blendEnable = VK_TRUE;
  blend.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
  blend.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  blend.colorBlendOp = VK_BLEND_OP_ADD;
  blend.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
  blend.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  blend.alphaBlendOp = VK_BLEND_OP_ADD;
  blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo cb{};
  cb.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO;
  cb.attachmentCount = 1;
  cb.pAttachments = &blend;
  const VkDynamicState dyn[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo ds{};
  ds.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO;
  ds.dynamicStateCount = 2;
  ds.pDynamicStates = dyn;
  VkGraphicsPipelineCreateInfo gp{};
  gp.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO;
  gp.stageCount = 2;
  gp.pStages = stages;
  gp.pVertexInputState = &vi;
  gp.pInputAssemblyState = &ia;
  gp.pViewportState = &vp;
  gp.pRasterizationState = &rs;
  gp.pMultisampleState = &ms;
  gp.pColorBlendState = &cb;
  gp.pDynamicState = &ds;
  gp.layout = layout.get();
  gp.renderPass = render_pass.get();
  VkPipeline p = VK_NULL_HANDLE;
  vk::check(vkCreateGraphicsPipelines(dev, VK_NULL_HANDLE, 1, &gp, nullptr, &p), "vkCreateGraphicsPipelines (viewer)");
  pipeline = Owned<VkPipeline>(dev, p, [](VkDevice d, VkPipeline x) { vkDestroyPipeline(d, x, nullptr); });
}

void Presenter::Impl::record_draw(VkCommandBuffer cmd, ImDrawData* data, Frame& f) {
  const float fb_w = data->DisplaySize.x * data->FramebufferScale.x, fb_h = data->DisplaySize.y * data->FramebufferScale.y;
  if (fb_w <= 0 || fb_h <= 0 || data->TotalVtxCount == 0) return;
  const VkDeviceSize vbytes = static_cast<VkDeviceSize>(data->TotalVtxCount) * sizeof(ImDrawVert);
  const VkDeviceSize ibytes = static_cast<VkDeviceSize>(data->TotalIdxCount) * sizeof(ImDrawIdx);
  ensure(f.vertices, vbytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::kUpload);
  ensure(f.indices, ibytes, VK_BUFFER_USAGE_INDEX_BUFFER_BIT, vk::MemoryUse::kUpload);
  VkDeviceSize vo = 0, io = 0;
  for (int n = 0; n < data->CmdListsCount; ++n) {
    const ImDrawList* list = data->CmdLists[n];
    const VkDeviceSize vb = static_cast<VkDeviceSize>(list->VtxBuffer.Size) * sizeof(ImDrawVert);
    const VkDeviceSize ib = static_cast<VkDeviceSize>(list->IdxBuffer.Size) * sizeof(ImDrawIdx);
    f.vertices.write(list->VtxBuffer.Data, vb, vo);
    f.indices.write(list->IdxBuffer.Data, ib, io);
    vo += vb;
    io += ib;
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.get());
  const VkBuffer vbuf = f.vertices.handle();
  const VkDeviceSize zero = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &vbuf, &zero);
  vkCmdBindIndexBuffer(cmd, f.indices.handle(), 0, sizeof(ImDrawIdx) == 2 ? VK_INDEX_TYPE_UINT16 : VK_INDEX_TYPE_UINT32);
  const VkViewport viewport{0, 0, fb_w, fb_h, 0, 1};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  const float push[4] = {2.0f / data->DisplaySize.x, 2.0f / data->DisplaySize.y,
                         -1.0f - data->DisplayPos.x * 2.0f / data->DisplaySize.x,
                         -1.0f - data->DisplayPos.y * 2.0f / data->DisplaySize.y};
  vkCmdPushConstants(cmd, layout.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof push, push);

  const ImVec2 off = data->DisplayPos, scale = data->FramebufferScale;
  VkDescriptorSet bound = VK_NULL_HANDLE;
  int global_vtx = 0, global_idx = 0;
  for (int n = 0; n < data->CmdListsCount; ++n) {
    const ImDrawList* list = data->CmdLists[n];
    for (int c = 0; c < list->CmdBuffer.Size; ++c) {
      const ImDrawCmd& pcmd = list->CmdBuffer[c];
      if (pcmd.UserCallback) {
        if (pcmd.UserCallback != ImDrawCallback_ResetRenderState) pcmd.UserCallback(list, &pcmd);
        continue;
      }
      const float x0 = std::max(0.0f, (pcmd.ClipRect.x - off.x) * scale.x);
      const float y0 = std::max(0.0f, (pcmd.ClipRect.y - off.y) * scale.y);
      const float x1 = std::min(fb_w, (pcmd.ClipRect.z - off.x) * scale.x);
      const float y1 = std::min(fb_h, (pcmd.ClipRect.w - off.y) * scale.y);
      if (x1 <= x0 || y1 <= y0) continue;
      const VkRect2D scissor{{static_cast<int32_t>(x0), static_cast<int32_t>(y0)},
                             {static_cast<uint32_t>(x1 - x0), static_cast<uint32_t>(y1 - y0)}};
      vkCmdSetScissor(cmd, 0, 1, &scissor);
      VkDescriptorSet set = reinterpret_cast<VkDescriptorSet>(pcmd.TextureId);
      if (!set) set = font_set;
      if (set != bound) {
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout.get(), 0, 1, &set, 0, nullptr);
        bound = set;
      }
      vkCmdDrawIndexed(cmd, pcmd.ElemCount, 1, pcmd.IdxOffset + static_cast<uint32_t>(global_idx),
                       static_cast<int32_t>(pcmd.VtxOffset) + global_vtx, 0);
    }
    global_idx += list->IdxBuffer.Size;
    global_vtx += list->VtxBuffer.Size;
  }
}

// --- Presenter ----------------------------------------------------------------------------------

Presenter::Presenter(const vk::Context& context, GLFWwindow* window, bool vsync)
    : impl_(std::make_unique<Impl>(context, window, vsync)) {
  if (!context.surface()) throw vk::VulkanError("viewer: the Vulkan context was made without the window's surface");
  impl_->create_fixed();
  impl_->create_swapchain();
  ImGuiIO& io = ImGui::GetIO();
  io.BackendRendererName = "hsi_vulkan_volk";
  io.BackendFlags |= ImGuiBackendFlags_RendererHasVtxOffset;
}

Presenter::~Presenter() = default;

void Presenter::wait_idle() const { vkDeviceWaitIdle(impl_->dev); }

void Presenter::upload_fonts() {
  Impl& r = *impl_;
  ImGuiIO& io = ImGui::GetIO();
  unsigned char* pixels = nullptr;
  int w = 0, h = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
  vkDeviceWaitIdle(r.dev);
  r.font = make_texture(r.ctx, w, h);
  const VkDeviceSize bytes = static_cast<VkDeviceSize>(w) * h * 4;
  vk::Buffer staging(r.ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::kUpload);
  staging.write(pixels, bytes);
  r.ctx.submit_and_wait([&](VkCommandBuffer cmd) { record_upload(cmd, staging, r.font, VK_IMAGE_LAYOUT_UNDEFINED); });
  r.write_set(r.font_set, r.font);
  io.Fonts->SetTexID(reinterpret_cast<ImTextureID>(r.font_set));
}

void Presenter::set_frame_image(const vk::RgbaImage& image) {
  impl_->pending = image;
  impl_->has_pending = !image.empty();
}

ImTextureID Presenter::frame_texture() const { return reinterpret_cast<ImTextureID>(impl_->frame_set); }
int Presenter::frame_width() const { return impl_->frame.width; }
int Presenter::frame_height() const { return impl_->frame.height; }

bool Presenter::present(ImDrawData* data, vk::RgbaImage* capture) {
  Impl& r = *impl_;
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(r.window, &fw, &fh);
  if (fw <= 0 || fh <= 0) return false;
  if (!r.swapchain || r.extent.width != static_cast<uint32_t>(fw) || r.extent.height != static_cast<uint32_t>(fh)) {
    vkDeviceWaitIdle(r.dev);
    r.create_swapchain();
    if (r.extent.width == 0) return false;
  }
  Impl::Frame& f = r.frames[static_cast<size_t>(r.frame_index)];
  const VkFence fence = f.fence.get();
  vk::check(vkWaitForFences(r.dev, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (viewer)");

  uint32_t image_index = 0;
  VkResult acq = vkAcquireNextImageKHR(r.dev, r.swapchain, UINT64_MAX, f.acquired.get(), VK_NULL_HANDLE, &image_index);
  if (acq == VK_ERROR_OUT_OF_DATE_KHR) {
    vkDeviceWaitIdle(r.dev);
    r.create_swapchain();
    return false;
  }
  if (acq != VK_SUBOPTIMAL_KHR) vk::check(acq, "vkAcquireNextImageKHR");
  vk::check(vkResetFences(r.dev, 1, &fence), "vkResetFences (viewer)");

  // A new frame image: (re)create the texture at its size, stage the pixels.
  bool upload = false;
  VkImageLayout upload_from = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  if (r.has_pending) {
    if (r.frame.width != r.pending.width || r.frame.height != r.pending.height) {
      vkDeviceWaitIdle(r.dev);  // the old texture may be in use by the other frame in flight
      r.frame = make_texture(r.ctx, r.pending.width, r.pending.height);
      r.write_set(r.frame_set, r.frame);
      upload_from = VK_IMAGE_LAYOUT_UNDEFINED;
    }
    r.ensure(f.staging, r.pending.pixels.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::kUpload);
    f.staging.write(r.pending.pixels.data(), r.pending.pixels.size());
    r.has_pending = false;
    upload = true;
  }

  const VkCommandBuffer cmd = f.cmd;
  vk::check(vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer (viewer)");
  VkCommandBufferBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vk::check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer (viewer)");
  if (upload) record_upload(cmd, f.staging, r.frame, upload_from);

  VkClearValue clear{};
  clear.color = {{0.10f, 0.11f, 0.13f, 1.0f}};
  VkRenderPassBeginInfo rp{};
  rp.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
  rp.renderPass = r.render_pass.get();
  rp.framebuffer = r.framebuffers[image_index].get();
  rp.renderArea = {{0, 0}, r.extent};
  rp.clearValueCount = 1;
  rp.pClearValues = &clear;
  vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
  r.record_draw(cmd, data, f);
  vkCmdEndRenderPass(cmd);

  const bool grab = capture && r.can_capture;
  if (capture && !r.can_capture)
    throw vk::VulkanError("viewer: the window's swapchain images cannot be copied (no TRANSFER_SRC usage): no screenshot");
  const VkImage image = r.images[image_index];
  const uint32_t w = r.extent.width, h = r.extent.height;
  if (grab) {
    r.ensure(f.readback, static_cast<VkDeviceSize>(w) * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::kReadback);
    vk::image_barrier(cmd, image, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, 0,
                      VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {w, h, 1};
    vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, f.readback.handle(), 1, &copy);
    vk::image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                      VK_ACCESS_TRANSFER_READ_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
    vk::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                       VK_ACCESS_HOST_READ_BIT);
  }
  vk::check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer (viewer)");

  const VkSemaphore wait = f.acquired.get(), signal = r.rendered[image_index].get();
  const VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSubmitInfo submit{};
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &wait;
  submit.pWaitDstStageMask = &wait_stage;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &signal;
  vk::check(vkQueueSubmit(r.ctx.queue(), 1, &submit, fence), "vkQueueSubmit (viewer)");

  VkPresentInfoKHR present{};
  present.sType = VK_STRUCTURE_TYPE_PRESENT_INFO_KHR;
  present.waitSemaphoreCount = 1;
  present.pWaitSemaphores = &signal;
  present.swapchainCount = 1;
  present.pSwapchains = &r.swapchain;
  present.pImageIndices = &image_index;
  const VkResult pr = vkQueuePresentKHR(r.ctx.queue(), &present);
  r.frame_index = (r.frame_index + 1) % kFramesInFlight;

  if (grab) {
    vk::check(vkWaitForFences(r.dev, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (capture)");
    vk::RgbaImage out(static_cast<int>(w), static_cast<int>(h));
    f.readback.read(out.pixels.data(), out.pixels.size());
    const bool bgra = r.format.format == VK_FORMAT_B8G8R8A8_UNORM || r.format.format == VK_FORMAT_B8G8R8A8_SRGB;
    for (size_t i = 0; i < out.pixels.size(); i += 4) {
      if (bgra) std::swap(out.pixels[i], out.pixels[i + 2]);
      out.pixels[i + 3] = 255;
    }
    *capture = std::move(out);
  }
  if (pr == VK_ERROR_OUT_OF_DATE_KHR || pr == VK_SUBOPTIMAL_KHR) {
    vkDeviceWaitIdle(r.dev);
    r.create_swapchain();
  } else {
    vk::check(pr, "vkQueuePresentKHR");
  }
  return true;
}

}  // namespace hsi::viewer
