// Swapchain presentation and the ImGui renderer (see presenter.h).
#include "presenter.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "hsi/compute/command_buffer.h"
#include "hsi/compute/descriptor_set.h"
#include "hsi/compute/framebuffer.h"
#include "hsi/compute/graphics_pipeline.h"
#include "hsi/compute/image.h"
#include "hsi/compute/pipeline_layout.h"
#include "hsi/compute/render_pass.h"
#include "hsi/compute/sampler.h"
#include "hsi/compute/sync.h"
#include "hsi/viewer/spirv/viewer_ui_frag.h"
#include "hsi/viewer/spirv/viewer_ui_vert.h"

namespace hsi::viewer {

namespace {

constexpr int kFramesInFlight = 2;

template <class T>
using Owned = compute::DeviceHandle<T>;

// A UI texture: the font atlas, the rendered frame, or a 1 × 1 white placeholder.
compute::Image make_texture(const compute::Context& ctx, int w, int h) {
  compute::ImageInfo info;
  info.width = static_cast<uint32_t>(w);
  info.height = static_cast<uint32_t>(h);
  return compute::Image(ctx, info);
}

// Records the copy of `staging` into `tex` (whole image), from `from` to shader-read.
void record_upload(VkCommandBuffer cmd, const compute::Buffer& staging, const compute::Image& tex, VkImageLayout from) {
  tex.record_upload(cmd, staging, from, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT);
}

int width_of(const compute::Image& image) { return image ? static_cast<int>(image.info().width) : 0; }
int height_of(const compute::Image& image) { return image ? static_cast<int>(image.info().height) : 0; }

}  // namespace

struct Presenter::Impl {
  const compute::Context& ctx;
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
  std::vector<compute::Framebuffer> framebuffers;
  std::vector<Owned<VkSemaphore>> rendered;  // per swapchain image: drawing done, present may start
  compute::RenderPass render_pass;
  compute::GraphicsPipeline pipeline;

  // Fixed objects. The descriptor sets are ImGui's texture ids.
  compute::Sampler sampler;
  compute::PipelineLayout layout;  // binding 0: the texture; push constants: scale and translation
  compute::DescriptorSet font_set, frame_set;
  compute::Image font, frame, blank;

  struct Frame {
    compute::CommandBuffer cmd;
    Owned<VkFence> fence;
    Owned<VkSemaphore> acquired;
    compute::Buffer vertices, indices, staging;
    compute::Buffer readback;
  };
  std::array<Frame, kFramesInFlight> frames;
  int frame_index = 0;

  // A frame image waiting for upload.
  RgbaImage pending;
  bool has_pending = false;

  Impl(const compute::Context& c, GLFWwindow* w, bool v) : ctx(c), window(w), vsync(v), dev(c.device()) {}

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
  void write_set(compute::DescriptorSet& set, const compute::Image& tex);
  void ensure(compute::Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage, compute::MemoryUse use) {
    if (b && b.size() >= bytes) return;
    b = compute::Buffer(ctx, std::max<VkDeviceSize>(bytes + bytes / 2, 4096), usage, use);
  }
  void record_draw(VkCommandBuffer cmd, ImDrawData* data, Frame& f);
};

void Presenter::Impl::create_fixed() {
  compute::SamplerInfo sampler_info;
  sampler_info.mipmap = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sampler_info.max_lod = 0;
  sampler = compute::Sampler(ctx, sampler_info);
  const compute::Binding texture{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT};
  layout = compute::PipelineLayout(ctx, std::span(&texture, 1), VK_SHADER_STAGE_VERTEX_BIT, 4 * sizeof(float));
  font_set = compute::DescriptorSet(ctx, layout);
  frame_set = compute::DescriptorSet(ctx, layout);

  for (Frame& f : frames) {
    f.cmd = compute::CommandBuffer(ctx);
    f.fence = compute::make_fence(ctx, true);  // signaled: nothing pending in this slot yet
    f.acquired = compute::make_semaphore(ctx);
  }

  // Until the first frame arrives, the frame set shows a 1 × 1 white texture.
  blank = make_texture(ctx, 1, 1);
  compute::Buffer staging(ctx, 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, compute::MemoryUse::kUpload);
  const uint8_t white[4] = {255, 255, 255, 255};
  staging.write(white, 4);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) { record_upload(cmd, staging, blank, VK_IMAGE_LAYOUT_UNDEFINED); });
  write_set(frame_set, blank);
  write_set(font_set, blank);
}

void Presenter::Impl::write_set(compute::DescriptorSet& set, const compute::Image& tex) {
  set.bind(0, tex.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, sampler.handle());
}

void Presenter::Impl::create_swapchain() {
  const VkPhysicalDevice phys = ctx.physical_device();
  const VkSurfaceKHR surface = ctx.surface();
  VkSurfaceCapabilitiesKHR caps;
  compute::check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(phys, surface, &caps), "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
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
    compute::check(vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &n, nullptr), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    std::vector<VkSurfaceFormatKHR> formats(n);
    compute::check(vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &n, formats.data()), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    if (formats.empty()) throw compute::VulkanError("viewer: the window's surface offers no formats");
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
    compute::check(vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &n, nullptr), "vkGetPhysicalDeviceSurfacePresentModesKHR");
    std::vector<VkPresentModeKHR> modes(n);
    compute::check(vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &n, modes.data()), "vkGetPhysicalDeviceSurfacePresentModesKHR");
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
  compute::check(vkCreateSwapchainKHR(dev, &info, nullptr, &sc), "vkCreateSwapchainKHR");
  destroy_swapchain();  // the old one (after the new one took over its images' presentation)
  swapchain = sc;
  extent = want;

  uint32_t n = 0;
  compute::check(vkGetSwapchainImagesKHR(dev, swapchain, &n, nullptr), "vkGetSwapchainImagesKHR");
  images.resize(n);
  compute::check(vkGetSwapchainImagesKHR(dev, swapchain, &n, images.data()), "vkGetSwapchainImagesKHR");

  if (!render_pass) {
    compute::RenderPassInfo pass;
    pass.color.format = format.format;
    pass.color.final_layout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
    // The acquire semaphore's wait is at colour output (and transfer): the layout
    // transition waits for it. Drawn before a capture copies the image (the default reader).
    pass.wait_stages = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    render_pass = compute::RenderPass(ctx, pass);
    create_pipeline();
  }

  for (VkImage image : images) {
    views.push_back(compute::make_image_view(ctx, image, format.format));
    const VkImageView v = views.back().get();
    framebuffers.emplace_back(ctx, render_pass, std::span(&v, 1), extent);
    rendered.push_back(compute::make_semaphore(ctx));
  }
}

void Presenter::Impl::create_pipeline() {
  compute::PipelineState state;  // viewport and scissor per draw command
  state.vertex_input.bindings = {{0, sizeof(ImDrawVert), VK_VERTEX_INPUT_RATE_VERTEX}};
  state.vertex_input.attributes = {{0, 0, VK_FORMAT_R32G32_SFLOAT, static_cast<uint32_t>(offsetof(ImDrawVert, pos))},
                                   {1, 0, VK_FORMAT_R32G32_SFLOAT, static_cast<uint32_t>(offsetof(ImDrawVert, uv))},
                                   {2, 0, VK_FORMAT_R8G8B8A8_UNORM, static_cast<uint32_t>(offsetof(ImDrawVert, col))}};
  state.blend.enable = true;  // ImGui's colours are straight alpha
  state.blend.src_color = VK_BLEND_FACTOR_SRC_ALPHA;
  pipeline = compute::GraphicsPipeline(ctx, layout, render_pass, viewer_ui_vert, viewer_ui_frag, state);
}

void Presenter::Impl::record_draw(VkCommandBuffer cmd, ImDrawData* data, Frame& f) {
  const float fb_w = data->DisplaySize.x * data->FramebufferScale.x, fb_h = data->DisplaySize.y * data->FramebufferScale.y;
  if (fb_w <= 0 || fb_h <= 0 || data->TotalVtxCount == 0) return;
  const VkDeviceSize vbytes = static_cast<VkDeviceSize>(data->TotalVtxCount) * sizeof(ImDrawVert);
  const VkDeviceSize ibytes = static_cast<VkDeviceSize>(data->TotalIdxCount) * sizeof(ImDrawIdx);
  ensure(f.vertices, vbytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, compute::MemoryUse::kUpload);
  ensure(f.indices, ibytes, VK_BUFFER_USAGE_INDEX_BUFFER_BIT, compute::MemoryUse::kUpload);
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
  pipeline.bind(cmd);
  const VkBuffer vbuf = f.vertices.handle();
  const VkDeviceSize zero = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &vbuf, &zero);
  vkCmdBindIndexBuffer(cmd, f.indices.handle(), 0, sizeof(ImDrawIdx) == 2 ? VK_INDEX_TYPE_UINT16 : VK_INDEX_TYPE_UINT32);
  const VkViewport viewport{0, 0, fb_w, fb_h, 0, 1};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  const float push[4] = {2.0f / data->DisplaySize.x, 2.0f / data->DisplaySize.y,
                         -1.0f - data->DisplayPos.x * 2.0f / data->DisplaySize.x,
                         -1.0f - data->DisplayPos.y * 2.0f / data->DisplaySize.y};
  layout.push(cmd, push, sizeof push);

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
      if (!set) set = font_set.handle();
      if (set != bound) {
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout.handle(), 0, 1, &set, 0, nullptr);
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

Presenter::Presenter(const compute::Context& context, GLFWwindow* window, bool vsync)
    : impl_(std::make_unique<Impl>(context, window, vsync)) {
  if (!context.surface()) throw compute::VulkanError("viewer: the Vulkan context was made without the window's surface");
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
  compute::Buffer staging(r.ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, compute::MemoryUse::kUpload);
  staging.write(pixels, bytes);
  r.ctx.submit_and_wait([&](VkCommandBuffer cmd) { record_upload(cmd, staging, r.font, VK_IMAGE_LAYOUT_UNDEFINED); });
  r.write_set(r.font_set, r.font);
  io.Fonts->SetTexID(reinterpret_cast<ImTextureID>(r.font_set.handle()));
}

void Presenter::set_frame_image(const RgbaImage& image) {
  impl_->pending = image;
  impl_->has_pending = !image.empty();
}

ImTextureID Presenter::frame_texture() const { return reinterpret_cast<ImTextureID>(impl_->frame_set.handle()); }
int Presenter::frame_width() const { return width_of(impl_->frame); }
int Presenter::frame_height() const { return height_of(impl_->frame); }

bool Presenter::present(ImDrawData* data, RgbaImage* capture) {
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
  compute::check(vkWaitForFences(r.dev, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (viewer)");

  uint32_t image_index = 0;
  VkResult acq = vkAcquireNextImageKHR(r.dev, r.swapchain, UINT64_MAX, f.acquired.get(), VK_NULL_HANDLE, &image_index);
  if (acq == VK_ERROR_OUT_OF_DATE_KHR) {
    vkDeviceWaitIdle(r.dev);
    r.create_swapchain();
    return false;
  }
  if (acq != VK_SUBOPTIMAL_KHR) compute::check(acq, "vkAcquireNextImageKHR");
  compute::check(vkResetFences(r.dev, 1, &fence), "vkResetFences (viewer)");

  // A new frame image: (re)create the texture at its size, stage the pixels.
  bool upload = false;
  VkImageLayout upload_from = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  if (r.has_pending) {
    if (width_of(r.frame) != r.pending.width || height_of(r.frame) != r.pending.height) {
      vkDeviceWaitIdle(r.dev);  // the old texture may be in use by the other frame in flight
      r.frame = make_texture(r.ctx, r.pending.width, r.pending.height);
      r.write_set(r.frame_set, r.frame);
      upload_from = VK_IMAGE_LAYOUT_UNDEFINED;
    }
    r.ensure(f.staging, r.pending.pixels.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, compute::MemoryUse::kUpload);
    f.staging.write(r.pending.pixels.data(), r.pending.pixels.size());
    r.has_pending = false;
    upload = true;
  }

  const VkCommandBuffer cmd = f.cmd.handle();
  f.cmd.begin();
  if (upload) record_upload(cmd, f.staging, r.frame, upload_from);

  r.render_pass.begin(cmd, r.framebuffers[image_index], {0.10f, 0.11f, 0.13f, 1.0f});
  r.record_draw(cmd, data, f);
  vkCmdEndRenderPass(cmd);

  const bool grab = capture && r.can_capture;
  if (capture && !r.can_capture)
    throw compute::VulkanError("viewer: the window's swapchain images cannot be copied (no TRANSFER_SRC usage): no screenshot");
  const VkImage image = r.images[image_index];
  const uint32_t w = r.extent.width, h = r.extent.height;
  if (grab) {
    r.ensure(f.readback, static_cast<VkDeviceSize>(w) * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, compute::MemoryUse::kReadback);
    compute::image_barrier(cmd, image, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, 0,
                      VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {w, h, 1};
    vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, f.readback.handle(), 1, &copy);
    compute::image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                      VK_ACCESS_TRANSFER_READ_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
    compute::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                       VK_ACCESS_HOST_READ_BIT);
  }
  f.cmd.end();

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
  compute::check(vkQueueSubmit(r.ctx.queue(), 1, &submit, fence), "vkQueueSubmit (viewer)");

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
    compute::check(vkWaitForFences(r.dev, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (capture)");
    RgbaImage out(static_cast<int>(w), static_cast<int>(h));
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
    compute::check(pr, "vkQueuePresentKHR");
  }
  return true;
}

}  // namespace hsi::viewer
