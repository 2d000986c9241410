// Offscreen renderer (see renderer.h and shaders/render_*.{vert,frag}). Graphics
// rasterizer: a render pass with a 4× MSAA colour attachment resolved into a
// single-sample image that is copied to host-visible memory; three pipelines
// (textured mesh, boundary lines, handle discs) over one descriptor set whose
// position and distortion buffers are the dense evaluation's outputs. Compute
// rasterizer (shaders/raster*.comp): the mesh's triangles into a visibility buffer,
// then shaded and resolved straight into that single-sample image, on which a
// single-sample render pass draws the lines and discs. Colours are premultiplied
// throughout (texture, blending, clear colour) and un-premultiplied on the way out.
#include "hsi/compute/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>

#include "hsi/compute/spirv/raster_f32.h"
#include "hsi/compute/spirv/raster_f64.h"
#include "hsi/compute/spirv/raster_resolve_f32.h"
#include "hsi/compute/spirv/raster_resolve_f64.h"
#include "hsi/compute/spirv/render_disc_frag.h"
#include "hsi/compute/spirv/render_disc_vert_f32.h"
#include "hsi/compute/spirv/render_disc_vert_f64.h"
#include "hsi/compute/spirv/render_line_frag.h"
#include "hsi/compute/spirv/render_line_vert_f32.h"
#include "hsi/compute/spirv/render_line_vert_f64.h"
#include "hsi/compute/spirv/render_mesh_frag.h"
#include "hsi/compute/spirv/render_mesh_vert_f32.h"
#include "hsi/compute/spirv/render_mesh_vert_f64.h"

namespace hsi::vk {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr VkFormat kColorFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr int kMaxSide = 16384;

// Mirrors `Push` in shaders/render_common.glsl (std430 offsets).
struct RenderPush {
  float color[4];
  float color2[4];
  float scale[2];
  float offset[2];
  float viewport[2];
  float size_px, size2_px;
  float dist_lo, dist_inv;
  float overlay_alpha;
  uint32_t flags;
  uint32_t first;       // discs: the first handle in f; the mesh: the uncertified border's width (0: none)
  float pad_[3];
  float background[4];  // the mesh: premultiplied background and border, which its top layer is blended over
  float border_color[4];
};
static_assert(sizeof(RenderPush) == 128);  // Vulkan's guaranteed maxPushConstantsSize
// Shading flags (shaders/render_shade.glsl).
constexpr uint32_t kTextured = 1u, kDistortion = 2u, kUncertified = 4u;
// Mirrors `Push` in shaders/raster_common.glsl (std430 offsets).
struct RasterPush {
  float background[4];
  float border_color[4];
  float fill[4];
  float scale[2];
  float offset[2];
  uint32_t width, height, samples, triangles;
  float dist_lo, dist_inv, overlay_alpha;
  uint32_t flags, border_px, pass;
};
static_assert(sizeof(RasterPush) == 104);
// Invocations per triangle in raster.comp's pass 0 (kLanes there).
constexpr uint32_t kRasterLanes = 4;
// The uncertified frame's border (opaque, so premultiplied as it is).
constexpr float kBorderRed[4] = {0.86f, 0.04f, 0.04f, 1.0f};

// What a frame's passes share: the view (world -> pixels), the colour map and the
// shape's flags; the rest is per draw.
RenderPush frame_push(const View& view, const RenderStyle& style, int width, int height, bool textured) {
  RenderPush pc{};
  const double s = view.pixels_per_unit;
  pc.scale[0] = static_cast<float>(s);
  pc.scale[1] = static_cast<float>(-s);
  pc.offset[0] = static_cast<float>(view.pixel_center.real() - s * view.world_center.real());
  pc.offset[1] = static_cast<float>(view.pixel_center.imag() + s * view.world_center.imag());
  pc.viewport[0] = static_cast<float>(width);
  pc.viewport[1] = static_cast<float>(height);
  pc.dist_lo = static_cast<float>(style.distortion_lo);
  pc.dist_inv = static_cast<float>(1.0 / (style.distortion_hi - style.distortion_lo));
  pc.overlay_alpha = std::clamp(style.distortion_opacity, 0.0f, 1.0f);
  pc.flags = (textured ? kTextured : 0u) | ((style.overlays & kOverlayDistortion) ? kDistortion : 0u) |
             (style.uncertified ? kUncertified : 0u);
  return pc;
}
constexpr VkShaderStageFlags kPushStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

template <class T>
using Destroy = void (*)(VkDevice, T);

template <class T>
DeviceHandle<T> own(VkDevice d, T handle, Destroy<T> destroy) {
  return DeviceHandle<T>(d, handle, destroy);
}

// A device image with its memory and a view (destroyed view, image, memory).
struct Image {
  DeviceHandle<VkDeviceMemory> memory;
  DeviceHandle<VkImage> image;
  DeviceHandle<VkImageView> view;
  uint32_t mips = 1;

  Image() = default;
  Image(Image&&) = default;
  Image& operator=(Image&& o) noexcept {
    if (this != &o) {
      reset();  // view, image, then memory (member-wise assignment would free the memory first)
      memory = std::move(o.memory);
      image = std::move(o.image);
      view = std::move(o.view);
      mips = o.mips;
    }
    return *this;
  }
  ~Image() { reset(); }
  void reset() {
    view.reset();
    image.reset();
    memory.reset();
  }
};

Image make_image(const Context& ctx, uint32_t w, uint32_t h, VkImageUsageFlags usage, VkSampleCountFlagBits samples,
                 uint32_t mips, VkMemoryPropertyFlags preferred = 0) {
  const VkDevice dev = ctx.device();
  Image img;
  img.mips = mips;
  VkImageCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = kColorFormat;
  info.extent = {w, h, 1};
  info.mipLevels = mips;
  info.arrayLayers = 1;
  info.samples = samples;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage raw = VK_NULL_HANDLE;
  check(vkCreateImage(dev, &info, nullptr, &raw), "vkCreateImage");
  // Declared before `image`, so memory is freed after the image is destroyed.
  DeviceHandle<VkImage> image = own<VkImage>(dev, raw, [](VkDevice d, VkImage i) { vkDestroyImage(d, i, nullptr); });
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(dev, raw, &req);
  VkMemoryAllocateInfo alloc{};
  alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = ctx.memory_type(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | preferred);
  VkDeviceMemory mem = VK_NULL_HANDLE;
  check(vkAllocateMemory(dev, &alloc, nullptr, &mem), "vkAllocateMemory (image)");
  img.memory = own<VkDeviceMemory>(dev, mem, [](VkDevice d, VkDeviceMemory m) { vkFreeMemory(d, m, nullptr); });
  check(vkBindImageMemory(dev, raw, mem, 0), "vkBindImageMemory");
  img.image = std::move(image);

  VkImageViewCreateInfo view{};
  view.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
  view.image = raw;
  view.viewType = VK_IMAGE_VIEW_TYPE_2D;
  view.format = kColorFormat;
  view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, mips, 0, 1};
  VkImageView raw_view = VK_NULL_HANDLE;
  check(vkCreateImageView(dev, &view, nullptr, &raw_view), "vkCreateImageView");
  img.view = own<VkImageView>(dev, raw_view, [](VkDevice d, VkImageView v) { vkDestroyImageView(d, v, nullptr); });
  return img;
}

// A device-local buffer holding `bytes` (through a staging copy unless the memory
// is host-visible).
Buffer static_buffer(const Context& ctx, VkBufferUsageFlags usage, const void* data, VkDeviceSize bytes) {
  Buffer b(ctx, std::max<VkDeviceSize>(bytes, 16), usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kDeviceLocal);
  if (bytes == 0) return b;
  if (b.host_visible()) {
    b.write(data, bytes);
    return b;
  }
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::kUpload);
  staging.write(data, bytes);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    const VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(cmd, staging.handle(), b.handle(), 1, &region);
    memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                   VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
  });
  return b;
}

// A sampled, mipmapped texture from straight-alpha RGBA (premultiplied on upload,
// mip levels by linear blits of the premultiplied colours).
Image make_texture(const Context& ctx, const RgbaImage& src) {
  const uint32_t w = static_cast<uint32_t>(src.width), h = static_cast<uint32_t>(src.height);
  uint32_t mips = 1;
  while ((std::max(w, h) >> mips) > 0) ++mips;
  Image tex = make_image(ctx, w, h,
                         VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                         VK_SAMPLE_COUNT_1_BIT, mips);
  std::vector<uint8_t> pre(src.pixels.size());
  for (size_t i = 0; i < pre.size(); i += 4) {
    const unsigned a = src.pixels[i + 3];
    for (size_t c = 0; c < 3; ++c) pre[i + c] = static_cast<uint8_t>((src.pixels[i + c] * a + 127) / 255);
    pre[i + 3] = static_cast<uint8_t>(a);
  }
  Buffer staging(ctx, pre.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::kUpload);
  staging.write(pre.data(), pre.size());
  const VkImage image = tex.image.get();
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    image_barrier(cmd, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                  VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, mips);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {w, h, 1};
    vkCmdCopyBufferToImage(cmd, staging.handle(), image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
    int32_t mw = static_cast<int32_t>(w), mh = static_cast<int32_t>(h);
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
      vkCmdBlitImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                     &blit, VK_FILTER_LINEAR);
      mw = nw;
      mh = nh;
    }
    if (mips > 1)
      image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_ACCESS_TRANSFER_READ_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, mips - 1);
    image_barrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                  VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                  VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, mips - 1, 1);
  });
  return tex;
}

DeviceHandle<VkShaderModule> shader_module(VkDevice dev, std::span<const uint32_t> code) {
  VkShaderModuleCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
  info.codeSize = code.size_bytes();
  info.pCode = code.data();
  VkShaderModule m = VK_NULL_HANDLE;
  check(vkCreateShaderModule(dev, &info, nullptr, &m), "vkCreateShaderModule");
  return own<VkShaderModule>(dev, m, [](VkDevice d, VkShaderModule s) { vkDestroyShaderModule(d, s, nullptr); });
}

std::array<float, 4> premultiplied(const std::array<float, 4>& c) { return {c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]}; }

}  // namespace

// --- colour map, view ----------------------------------------------------------------------

std::array<double, 3> colormap(double t) {
  t = std::clamp(std::isnan(t) ? 1.0 : t, 0.0, 1.0);
  static constexpr double c[7][3] = {
      {0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
      {0.1050930431085774, 1.404613529898575, 1.384590162594685},
      {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
      {-4.634230498983486, -5.799100973351585, -19.33244095627987},
      {6.228269936347081, 14.17993336680509, 56.69055260068105},
      {4.776384997670288, -13.74514537774601, -65.35303263337234},
      {-5.435455855934631, 4.645852612178535, 26.3124352495832}};
  std::array<double, 3> out{};
  for (int k = 0; k < 3; ++k) {
    double v = c[6][k];
    for (int i = 5; i >= 0; --i) v = c[i][k] + t * v;
    out[static_cast<size_t>(k)] = std::clamp(v, 0.0, 1.0);
  }
  return out;
}

View View::fit(const BoundingBox& world, int width, int height, double margin_px, double bottom_px) {
  const cd ext = world.hi - world.lo;
  const double aw = width - 2 * margin_px, ah = height - 2 * margin_px - bottom_px;
  if (!(std::isfinite(ext.real()) && std::isfinite(ext.imag())) || (ext.real() <= 0 && ext.imag() <= 0))
    throw InputError("View::fit: the box to show is empty or not finite");
  if (aw <= 1 || ah <= 1)
    throw InputError("View::fit: a " + std::to_string(width) + " x " + std::to_string(height) +
                     " image leaves no room inside its margins");
  double s = std::numeric_limits<double>::infinity();
  if (ext.real() > 0) s = std::min(s, aw / ext.real());
  if (ext.imag() > 0) s = std::min(s, ah / ext.imag());
  View v;
  v.world_center = 0.5 * (world.lo + world.hi);
  v.pixels_per_unit = s;
  v.pixel_center = {0.5 * width, margin_px + 0.5 * ah};
  return v;
}

// --- renderer -----------------------------------------------------------------------------

struct Renderer::Impl {
  // Destroyed in reverse order: pipelines before their layout, views before images.
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
  DeviceHandle<VkRenderPass> render_pass;
  Image msaa, resolve;  // msaa unused (empty) with 1 sample
  DeviceHandle<VkFramebuffer> framebuffer;
  DeviceHandle<VkSampler> sampler;
  Image texture, white;
  DeviceHandle<VkDescriptorSetLayout> set_layout;
  DeviceHandle<VkDescriptorPool> pool;
  VkDescriptorSet set = VK_NULL_HANDLE;
  DeviceHandle<VkPipelineLayout> layout;
  DeviceHandle<VkPipeline> mesh, line, disc;  // mesh: graphics rasterizer only
  Buffer uv, index, segments;
  // Compute rasterizer: the visibility buffer (a triangle id per sample), the queue
  // of large triangles (count, indices), the two passes' pipelines and their
  // descriptor sets (destroyed before the pipelines).
  Buffer vis, large;
  ComputePipeline raster, resolve_pass;
  DescriptorSet raster_set, resolve_set;
  Buffer readback;
  // Given geometry (render(positions, kappa, ...)): the layouts of the evaluation's
  // f and fields outputs, host-written.
  Buffer given_f, given_fields;
  size_t given_capacity = 0;  // points they hold
};

Renderer::~Renderer() = default;

Renderer::Renderer(const Context& context, int width, int height, const RendererOptions& options)
    : context_(&context), width_(width), height_(height), eval_(context, options.evaluation),
      impl_(std::make_unique<Impl>()) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw InputError("renderer: image size " + std::to_string(width) + " x " + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxSide));
  const VkDevice dev = context.device();
  {
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &n, nullptr);
    std::vector<VkQueueFamilyProperties> families(n);
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &n, families.data());
    if (context.queue_family() >= n || !(families[context.queue_family()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
      throw VulkanUnavailable("renderer: the Vulkan device " + context.info().name +
                              " has no queue that can both compute and draw");
  }
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(context.physical_device(), &props);
  const auto pick_samples = [&](VkSampleCountFlags supported) {
    for (int s : {8, 4, 2, 1})
      if (s <= options.msaa_samples && (supported & static_cast<VkSampleCountFlags>(s))) return s;
    return 1;
  };
  const uint32_t w = static_cast<uint32_t>(width), h = static_cast<uint32_t>(height);
  // The compute rasterizer takes any of 1, 2, 4, 8 samples; its visibility buffer
  // must fit in one storage buffer.
  const int compute_samples = pick_samples(VK_SAMPLE_COUNT_1_BIT | VK_SAMPLE_COUNT_2_BIT | VK_SAMPLE_COUNT_4_BIT |
                                           VK_SAMPLE_COUNT_8_BIT);
  const uint64_t vis_bytes = uint64_t{w} * h * static_cast<uint64_t>(compute_samples) * sizeof(uint32_t);
  const bool vis_fits = vis_bytes <= props.limits.maxStorageBufferRange;
  switch (options.rasterizer) {
    case Rasterizer::kCompute:
      if (!vis_fits)
        throw VulkanError("renderer: the compute rasterizer's visibility buffer (" + std::to_string(width) + " x " +
                          std::to_string(height) + " pixels x " + std::to_string(compute_samples) + " samples x 4 bytes = " +
                          std::to_string(vis_bytes) + " bytes) exceeds " + context.info().name +
                          "'s maxStorageBufferRange (" + std::to_string(props.limits.maxStorageBufferRange) +
                          "); use fewer samples, a smaller image or the graphics rasterizer");
      rasterizer_ = Rasterizer::kCompute;
      break;
    case Rasterizer::kGraphics: rasterizer_ = Rasterizer::kGraphics; break;
    case Rasterizer::kAuto:
      rasterizer_ = !context.info().is_cpu() && vis_fits ? Rasterizer::kCompute : Rasterizer::kGraphics;
      break;
  }
  const bool compute = rasterizer_ == Rasterizer::kCompute;
  Impl& r = *impl_;
  samples_ = compute ? compute_samples : pick_samples(props.limits.framebufferColorSampleCounts);
  // The graphics passes' sample count: the compute path draws its lines and discs
  // into the resolved image.
  r.samples = compute ? VK_SAMPLE_COUNT_1_BIT : static_cast<VkSampleCountFlagBits>(samples_);
  const bool msaa = r.samples != VK_SAMPLE_COUNT_1_BIT;

  // --- render pass: MSAA colour, resolved into the image we read back ------------------
  // (Compute rasterizer: the resolved image itself, as the compute passes left it.)
  std::vector<VkAttachmentDescription> attachments;
  VkAttachmentDescription color{};
  color.format = kColorFormat;
  color.samples = r.samples;
  color.loadOp = compute ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR;
  color.storeOp = msaa ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
  color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  color.initialLayout = compute ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_UNDEFINED;
  color.finalLayout = msaa ? VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  attachments.push_back(color);
  if (msaa) {
    VkAttachmentDescription resolve = color;
    resolve.samples = VK_SAMPLE_COUNT_1_BIT;
    resolve.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    resolve.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    resolve.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    attachments.push_back(resolve);
  }
  const VkAttachmentReference color_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  const VkAttachmentReference resolve_ref{1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &color_ref;
  subpass.pResolveAttachments = msaa ? &resolve_ref : nullptr;
  VkSubpassDependency deps[2] = {};
  // The previous frame's copy out of the image (a read) before this frame's writes.
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].srcAccessMask = 0;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
  if (compute) {  // the compute passes' writes of the image before the lines and discs blend onto it
    deps[0].srcStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    deps[0].srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  }
  // The rendered (resolved) image before the copy to the host.
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo rp{};
  rp.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
  rp.attachmentCount = static_cast<uint32_t>(attachments.size());
  rp.pAttachments = attachments.data();
  rp.subpassCount = 1;
  rp.pSubpasses = &subpass;
  rp.dependencyCount = 2;
  rp.pDependencies = deps;
  VkRenderPass raw_rp = VK_NULL_HANDLE;
  check(vkCreateRenderPass(dev, &rp, nullptr, &raw_rp), "vkCreateRenderPass");
  r.render_pass = own<VkRenderPass>(dev, raw_rp, [](VkDevice d, VkRenderPass p) { vkDestroyRenderPass(d, p, nullptr); });

  r.resolve = make_image(context, w, h,
                         VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                             (compute ? VkImageUsageFlags{VK_IMAGE_USAGE_STORAGE_BIT} : VkImageUsageFlags{0}),
                         VK_SAMPLE_COUNT_1_BIT, 1);
  std::vector<VkImageView> views;
  if (msaa) {
    r.msaa = make_image(context, w, h, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT,
                        r.samples, 1, VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT);
    views = {r.msaa.view.get(), r.resolve.view.get()};
  } else {
    views = {r.resolve.view.get()};
  }
  VkFramebufferCreateInfo fb{};
  fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
  fb.renderPass = raw_rp;
  fb.attachmentCount = static_cast<uint32_t>(views.size());
  fb.pAttachments = views.data();
  fb.width = w;
  fb.height = h;
  fb.layers = 1;
  VkFramebuffer raw_fb = VK_NULL_HANDLE;
  check(vkCreateFramebuffer(dev, &fb, nullptr, &raw_fb), "vkCreateFramebuffer");
  r.framebuffer = own<VkFramebuffer>(dev, raw_fb, [](VkDevice d, VkFramebuffer f) { vkDestroyFramebuffer(d, f, nullptr); });
  r.readback = Buffer(context, static_cast<VkDeviceSize>(w) * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kReadback);

  // --- sampler, placeholder texture ----------------------------------------------------------
  VkSamplerCreateInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
  si.magFilter = VK_FILTER_LINEAR;
  si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  si.maxLod = VK_LOD_CLAMP_NONE;
  VkSampler raw_sampler = VK_NULL_HANDLE;
  check(vkCreateSampler(dev, &si, nullptr, &raw_sampler), "vkCreateSampler");
  r.sampler = own<VkSampler>(dev, raw_sampler, [](VkDevice d, VkSampler s) { vkDestroySampler(d, s, nullptr); });
  r.white = make_texture(context, RgbaImage(1, 1, {255, 255, 255, 255}));

  // --- descriptor set: f, fields (the evaluation's outputs), texture, segments --------------
  const VkDescriptorSetLayoutBinding bindings[4] = {
      {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
      {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr},
      {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo sl{};
  sl.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  sl.bindingCount = 4;
  sl.pBindings = bindings;
  VkDescriptorSetLayout raw_sl = VK_NULL_HANDLE;
  check(vkCreateDescriptorSetLayout(dev, &sl, nullptr, &raw_sl), "vkCreateDescriptorSetLayout");
  r.set_layout = own<VkDescriptorSetLayout>(
      dev, raw_sl, [](VkDevice d, VkDescriptorSetLayout l) { vkDestroyDescriptorSetLayout(d, l, nullptr); });
  const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 3},
                                         {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1}};
  VkDescriptorPoolCreateInfo pi{};
  pi.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
  pi.maxSets = 1;
  pi.poolSizeCount = 2;
  pi.pPoolSizes = sizes;
  VkDescriptorPool raw_pool = VK_NULL_HANDLE;
  check(vkCreateDescriptorPool(dev, &pi, nullptr, &raw_pool), "vkCreateDescriptorPool");
  r.pool = own<VkDescriptorPool>(dev, raw_pool, [](VkDevice d, VkDescriptorPool p) { vkDestroyDescriptorPool(d, p, nullptr); });
  VkDescriptorSetAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
  ai.descriptorPool = raw_pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &raw_sl;
  check(vkAllocateDescriptorSets(dev, &ai, &r.set), "vkAllocateDescriptorSets");

  const VkPushConstantRange push{kPushStages, 0, sizeof(RenderPush)};
  VkPipelineLayoutCreateInfo li{};
  li.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
  li.setLayoutCount = 1;
  li.pSetLayouts = &raw_sl;
  li.pushConstantRangeCount = 1;
  li.pPushConstantRanges = &push;
  VkPipelineLayout raw_layout = VK_NULL_HANDLE;
  check(vkCreatePipelineLayout(dev, &li, nullptr, &raw_layout), "vkCreatePipelineLayout");
  r.layout = own<VkPipelineLayout>(dev, raw_layout, [](VkDevice d, VkPipelineLayout l) { vkDestroyPipelineLayout(d, l, nullptr); });

  // --- pipelines --------------------------------------------------------------------------------
  const bool f64 = eval_.double_precision();
  auto make_pipeline = [&](std::span<const uint32_t> vert, std::span<const uint32_t> frag, bool uv_input, bool blending) {
    const DeviceHandle<VkShaderModule> vs = shader_module(dev, vert), fs = shader_module(dev, frag);
    VkPipelineShaderStageCreateInfo stages[2] = {};
    stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vs.get();
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fs.get();
    stages[1].pName = "main";
    const VkVertexInputBindingDescription vb{0, 2 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX};
    const VkVertexInputAttributeDescription va{0, 0, VK_FORMAT_R32G32_SFLOAT, 0};
    VkPipelineVertexInputStateCreateInfo vi{};
    vi.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO;
    if (uv_input) {
      vi.vertexBindingDescriptionCount = 1;
      vi.pVertexBindingDescriptions = &vb;
      vi.vertexAttributeDescriptionCount = 1;
      vi.pVertexAttributeDescriptions = &va;
    }
    VkPipelineInputAssemblyStateCreateInfo ia{};
    ia.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO;
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    const VkViewport viewport{0, 0, static_cast<float>(w), static_cast<float>(h), 0, 1};
    const VkRect2D scissor{{0, 0}, {w, h}};
    VkPipelineViewportStateCreateInfo vp{};
    vp.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO;
    vp.viewportCount = 1;
    vp.pViewports = &viewport;
    vp.scissorCount = 1;
    vp.pScissors = &scissor;
    VkPipelineRasterizationStateCreateInfo rs{};
    rs.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO;
    rs.polygonMode = VK_POLYGON_MODE_FILL;
    rs.cullMode = VK_CULL_MODE_NONE;  // a folded (uncertified) frame has flipped triangles: draw them too
    rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    rs.lineWidth = 1;
    VkPipelineMultisampleStateCreateInfo ms{};
    ms.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO;
    ms.rasterizationSamples = r.samples;
    VkPipelineColorBlendAttachmentState blend{};
    blend.blendEnable = blending ? VK_TRUE : VK_FALSE;  // premultiplied "over" (the mesh: replace, see record_frame)
    blend.srcColorBlendFactor = VK_BLEND_FACTOR_ONE;
    blend.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    blend.colorBlendOp = VK_BLEND_OP_ADD;
    blend.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
    blend.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    blend.alphaBlendOp = VK_BLEND_OP_ADD;
    blend.colorWriteMask =
        VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo cb{};
    cb.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO;
    cb.attachmentCount = 1;
    cb.pAttachments = &blend;
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
    gp.layout = raw_layout;
    gp.renderPass = raw_rp;
    gp.subpass = 0;
    VkPipeline p = VK_NULL_HANDLE;
    check(vkCreateGraphicsPipelines(dev, VK_NULL_HANDLE, 1, &gp, nullptr, &p), "vkCreateGraphicsPipelines");
    return own<VkPipeline>(dev, p, [](VkDevice d, VkPipeline q) { vkDestroyPipeline(d, q, nullptr); });
  };
  using S = std::span<const uint32_t>;
  if (!compute)
    r.mesh = make_pipeline(f64 ? S(render_mesh_vert_f64) : S(render_mesh_vert_f32), S(render_mesh_frag), true, false);
  r.line = make_pipeline(f64 ? S(render_line_vert_f64) : S(render_line_vert_f32), S(render_line_frag), false, true);
  r.disc = make_pipeline(f64 ? S(render_disc_vert_f64) : S(render_disc_vert_f32), S(render_disc_frag), false, true);

  if (compute) {
    // Bindings of shaders/raster_common.glsl.
    constexpr VkDescriptorType kSb = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    const VkDescriptorType types[8] = {kSb, kSb, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kSb, kSb, kSb, kSb,
                                       VK_DESCRIPTOR_TYPE_STORAGE_IMAGE};
    r.raster = ComputePipeline(context, f64 ? S(raster_f64) : S(raster_f32), types, sizeof(RasterPush));
    r.resolve_pass = ComputePipeline(context, f64 ? S(raster_resolve_f64) : S(raster_resolve_f32), types, sizeof(RasterPush));
    r.raster_set = DescriptorSet(context, r.raster);
    r.resolve_set = DescriptorSet(context, r.resolve_pass);
    r.vis = Buffer(context, vis_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                   MemoryUse::kDeviceLocal);
  }
}

void Renderer::set_mesh(const TriMesh& mesh, std::span<const cd> handles) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    throw InputError("renderer: the mesh is empty (" + std::to_string(mesh.vertices.size()) + " vertices, " +
                     std::to_string(mesh.triangles.size()) + " triangles)");
  const int n = mesh.vertex_count();
  std::vector<uint32_t> indices;
  indices.reserve(mesh.triangles.size() * 3);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int v : mesh.triangles[t]) {
      if (v < 0 || v >= n)
        throw InputError("renderer: triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                         " outside 0.." + std::to_string(n - 1));
      indices.push_back(static_cast<uint32_t>(v));
    }
  std::vector<uint32_t> segments;
  segments.reserve(mesh.boundary_edges.size() * 2);
  for (size_t e = 0; e < mesh.boundary_edges.size(); ++e)
    for (int v : mesh.boundary_edges[e]) {
      if (v < 0 || v >= n)
        throw InputError("renderer: boundary edge " + std::to_string(e) + " has vertex index " + std::to_string(v) +
                         " outside 0.." + std::to_string(n - 1));
      segments.push_back(static_cast<uint32_t>(v));
    }
  for (size_t k = 0; k < handles.size(); ++k)
    if (!std::isfinite(handles[k].real()) || !std::isfinite(handles[k].imag()))
      throw InputError("renderer: handle " + std::to_string(k) + " is not finite");
  Impl& r = *impl_;
  r.index = static_buffer(*context_, VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, indices.data(),
                          indices.size() * sizeof(uint32_t));
  if (rasterizer_ == Rasterizer::kCompute) {
    r.large = Buffer(*context_, (1 + mesh.triangles.size()) * sizeof(uint32_t),
                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kDeviceLocal);
  }
  r.segments = static_buffer(*context_, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, segments.data(),
                             segments.size() * sizeof(uint32_t));
  rest_vertices_ = mesh.vertices;
  points_ = mesh.vertices;
  points_.insert(points_.end(), handles.begin(), handles.end());
  vertex_count_ = mesh.vertices.size();
  handle_count_ = handles.size();
  index_count_ = indices.size();
  segment_count_ = mesh.boundary_edges.size();
  uv_dirty_ = true;
}

void Renderer::set_texture(const RgbaImage& texture, const std::array<double, 4>& rect) {
  Impl& r = *impl_;
  if (texture.empty()) {
    r.texture = Image();
    has_texture_ = false;
    return;
  }
  if (texture.pixels.size() != static_cast<size_t>(texture.width) * static_cast<size_t>(texture.height) * 4)
    throw InputError("renderer: the texture's pixel data does not match its size");
  if (texture.width > kMaxSide || texture.height > kMaxSide)
    throw InputError("renderer: texture size " + std::to_string(texture.width) + " x " +
                     std::to_string(texture.height) + " is larger than " + std::to_string(kMaxSide));
  if (!(rect[2] > rect[0] && rect[3] > rect[1]) || !std::all_of(rect.begin(), rect.end(), [](double v) { return std::isfinite(v); }))
    throw InputError("renderer: the texture rectangle [x0, y0, x1, y1] needs x1 > x0 and y1 > y0, finite");
  r.texture = make_texture(*context_, texture);
  texture_rect_ = rect;
  has_texture_ = true;
  uv_dirty_ = true;
}

void Renderer::upload_uv() {
  const auto& [x0, y0, x1, y1] = texture_rect_;
  std::vector<float> uv;
  uv.reserve(2 * rest_vertices_.size());
  for (const cd& p : rest_vertices_) {
    uv.push_back(static_cast<float>((p.real() - x0) / (x1 - x0)));
    uv.push_back(static_cast<float>((y1 - p.imag()) / (y1 - y0)));  // row 0 is the top (y1)
  }
  impl_->uv = static_buffer(*context_, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, uv.data(),
                            uv.size() * sizeof(float));
  uv_dirty_ = false;
}

UnweldedMesh unweld(const TriMesh& mesh) {
  UnweldedMesh u;
  const size_t nt = mesh.triangles.size();
  u.mesh.vertices.reserve(3 * nt);
  u.mesh.triangles.reserve(nt);
  u.source.reserve(3 * nt);
  u.mesh.boundary_loop.reserve(3 * nt);
  // Each boundary edge (a, b) has the shape on its left: it is the edge a -> b of
  // exactly one counter-clockwise triangle.
  std::unordered_map<uint64_t, std::array<int, 2>> directed;
  directed.reserve(3 * nt);
  const auto key = [](int a, int b) { return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b); };
  for (size_t t = 0; t < nt; ++t) {
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][static_cast<size_t>(k)];
      tri[static_cast<size_t>(k)] = static_cast<int>(u.mesh.vertices.size());
      u.mesh.vertices.push_back(mesh.vertices[static_cast<size_t>(v)]);
      u.mesh.boundary_loop.push_back(mesh.boundary_loop.empty() ? -1 : mesh.boundary_loop[static_cast<size_t>(v)]);
      u.source.push_back(v);
    }
    for (int k = 0; k < 3; ++k)
      directed[key(mesh.triangles[t][static_cast<size_t>(k)], mesh.triangles[t][static_cast<size_t>((k + 1) % 3)])] = {
          tri[static_cast<size_t>(k)], tri[static_cast<size_t>((k + 1) % 3)]};
    u.mesh.triangles.push_back(tri);
  }
  u.mesh.boundary_edges.reserve(mesh.boundary_edges.size());
  for (const auto& [a, b] : mesh.boundary_edges) {
    const auto it = directed.find(key(a, b));
    if (it == directed.end())
      throw InputError("unweld: boundary edge (" + std::to_string(a) + ", " + std::to_string(b) +
                       ") is not an edge of a counter-clockwise triangle");
    u.mesh.boundary_edges.push_back(it->second);
  }
  return u;
}

RgbaImage Renderer::render(const Cage& cage, const HarmonicMap& map, const View& view, const RenderStyle& style) {
  frame(&cage, &map, handle_count_, view, style, true);
  return read_image();
}

RgbaImage Renderer::render(std::span<const cd> positions, std::span<const double> kappa, const View& view,
                           const RenderStyle& style, std::span<const cd> handle_positions) {
  const size_t handles = upload_given(positions, kappa, handle_positions);
  frame(nullptr, nullptr, handles, view, style, true);
  return read_image();
}

void Renderer::draw(std::span<const cd> positions, std::span<const double> kappa, const View& view,
                    const RenderStyle& style, std::span<const cd> handle_positions) {
  const size_t handles = upload_given(positions, kappa, handle_positions);
  frame(nullptr, nullptr, handles, view, style, false);
}

size_t Renderer::upload_given(std::span<const cd> positions, std::span<const double> kappa,
                              std::span<const cd> handle_positions) {
  if (points_.empty()) throw InputError("renderer: no mesh (call set_mesh first)");
  if (positions.size() != vertex_count_ || kappa.size() != vertex_count_)
    throw InputError("renderer: given geometry needs one position and one distortion per mesh vertex (the mesh has " +
                     std::to_string(vertex_count_) + " vertices; got " + std::to_string(positions.size()) +
                     " positions, " + std::to_string(kappa.size()) + " distortion values)");
  if (!handle_positions.empty() && handle_positions.size() != handle_count_)
    throw InputError("renderer: " + std::to_string(handle_positions.size()) + " handle positions for " +
                     std::to_string(handle_count_) + " handles (give one per handle, or none)");
  for (size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i].real()) || !std::isfinite(positions[i].imag()))
      throw InputError("renderer: given position " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < handle_positions.size(); ++i)
    if (!std::isfinite(handle_positions[i].real()) || !std::isfinite(handle_positions[i].imag()))
      throw InputError("renderer: given handle position " + std::to_string(i) + " is not finite");
  Impl& r = *impl_;
  const size_t n = vertex_count_ + handle_count_;
  const bool f64 = eval_.double_precision();
  const size_t real = f64 ? sizeof(double) : sizeof(float);
  if (r.given_capacity < n) {
    r.given_f = Buffer(*context_, 2 * real * n, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    r.given_fields = Buffer(*context_, 4 * real * n, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    r.given_capacity = n;
  }
  // f[i] = (x, y); fields[i] = (σ1, σ2, κ, E_SD) as the evaluation writes them. Only κ
  // is read by the shaders; σ1, σ2 and E_SD are NaN (not known here). Handles without
  // given positions stay at their rest positions (their discs are not drawn).
  std::vector<double> f(2 * n), fields(4 * n, std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < n; ++i) {
    const cd p = i < vertex_count_ ? positions[i]
                 : handle_positions.empty() ? points_[i]
                                            : handle_positions[i - vertex_count_];
    f[2 * i] = p.real();
    f[2 * i + 1] = p.imag();
    fields[4 * i + 2] = i < vertex_count_ ? kappa[i] : 1.0;
  }
  if (f64) {
    r.given_f.write(f.data(), f.size() * sizeof(double));
    r.given_fields.write(fields.data(), fields.size() * sizeof(double));
  } else {
    const std::vector<float> f32(f.begin(), f.end()), fields32(fields.begin(), fields.end());
    r.given_f.write(f32.data(), f32.size() * sizeof(float));
    r.given_fields.write(fields32.data(), fields32.size() * sizeof(float));
  }
  return handle_positions.size();
}

RgbaImage Renderer::read_image() {
  const auto t_read = Clock::now();
  RgbaImage out(width_, height_);
  impl_->readback.read(out.pixels.data(), out.pixels.size());
  for (size_t i = 0; i < out.pixels.size(); i += 4) {
    const unsigned a = out.pixels[i + 3];
    if (a == 255) continue;
    if (a == 0) {
      out.pixels[i] = out.pixels[i + 1] = out.pixels[i + 2] = 0;
      continue;
    }
    for (size_t c = 0; c < 3; ++c) out.pixels[i + c] = static_cast<uint8_t>(std::min(255u, (out.pixels[i + c] * 255 + a / 2) / a));
  }
  stats_.readback_ms = ms_since(t_read);
  return out;
}

void Renderer::draw(const Cage& cage, const HarmonicMap& map, const View& view, const RenderStyle& style) {
  frame(&cage, &map, handle_count_, view, style, false);
}

double round_distortion_hi(double hi) {
  const double span = std::max(hi - 1.0, 1e-3);
  const double base = std::pow(10.0, std::floor(std::log10(span / 4)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (4 * m * base >= span * (1 - 1e-12)) return 1.0 + 4 * m * base;
  return 1.0 + 40 * base;
}

void Renderer::record(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, const View& view,
                      const RenderStyle& style, bool mark_evaluation) {
  check_frame(view, style);
  stats_ = {};
  record_frame(cmd, &cage, &map, handle_count_, view, style, false, mark_evaluation);
}

void Renderer::check_frame(const View& view, const RenderStyle& style) const {
  if (points_.empty()) throw InputError("renderer: no mesh (call set_mesh first)");
  if (!(view.pixels_per_unit > 0) || !std::isfinite(view.pixels_per_unit))
    throw InputError("renderer: the view needs a finite positive scale");
  if (!(style.distortion_hi > style.distortion_lo))
    throw InputError("renderer: the distortion range needs hi > lo (got " + std::to_string(style.distortion_lo) +
                     ", " + std::to_string(style.distortion_hi) + ")");
}

void Renderer::frame(const Cage* cage, const HarmonicMap* map, size_t handles, const View& view, const RenderStyle& style,
                     bool copy_out) {
  check_frame(view, style);
  const auto t0 = Clock::now();
  stats_ = {};
  context_->submit_and_wait(
      [&](VkCommandBuffer cmd) { record_frame(cmd, cage, map, handles, view, style, copy_out, false); });
  stats_.gpu_ms = ms_since(t0) - stats_.upload_ms;
}

void Renderer::record_frame(VkCommandBuffer cmd, const Cage* cage, const HarmonicMap* map, size_t handles,
                            const View& view, const RenderStyle& style, bool copy_out, bool mark_evaluation) {
  Impl& r = *impl_;
  const auto t0 = Clock::now();
  if (uv_dirty_) upload_uv();
  const VkDevice dev = context_->device();
  RenderPush pc = frame_push(view, style, width_, height_, has_texture_);
  const float border = style.border_px > 0 ? style.border_px : std::max(4.0f, static_cast<float>(std::min(width_, height_)) / 64);
  const uint32_t border_px = std::min(static_cast<uint32_t>(std::lround(border)), static_cast<uint32_t>(std::min(width_, height_) / 2));
  const uint32_t w = static_cast<uint32_t>(width_), h = static_cast<uint32_t>(height_);

  if (cage) {
    // The previous frame's shaders read the evaluation's outputs; this frame rewrites them.
    constexpr VkPipelineStageFlags kReaders = VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    memory_barrier(cmd, kReaders, 0, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0);
    eval_.record_points(cmd, *cage, *map, points_);
    memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, kReaders,
                   VK_ACCESS_SHADER_READ_BIT);
    if (mark_evaluation) context_->mark(cmd);
  }
  // (Given geometry was written by the host before this submission, which makes it visible.)

  const Buffer& f = cage ? eval_.device_output(0) : r.given_f;
  const Buffer& fields = cage ? eval_.device_output(3) : r.given_fields;
  const bool compute = rasterizer_ == Rasterizer::kCompute;
  const bool lines = (style.overlays & kOverlayBoundary) && segment_count_ > 0 && style.boundary_width_px > 0;
  const bool discs = (style.overlays & kOverlayHandles) && handles > 0 && style.handle_radius_px > 0;
  if (compute) {
    record_compute_raster(cmd, f, fields, view, style, style.uncertified ? border_px : 0u);
    if (!lines && !discs) {  // nothing to draw over it: no render pass, just the layout the copy out expects
      image_barrier(cmd, r.resolve.image.get(), VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                    VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT);
      drawn_ = true;
      if (copy_out) record_copy_out(cmd);
      stats_.upload_ms = ms_since(t0);
      return;
    }
  }

  // The graphics set is not bound in any pending command buffer: point it at this frame's buffers.
  const VkDescriptorBufferInfo infos[3] = {{f.handle(), 0, VK_WHOLE_SIZE},
                                           {fields.handle(), 0, VK_WHOLE_SIZE},
                                           {r.segments.handle(), 0, VK_WHOLE_SIZE}};
  const VkDescriptorImageInfo image_info{r.sampler.get(), (has_texture_ ? r.texture : r.white).view.get(),
                                         VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet writes[4] = {};
  const uint32_t binding_of[4] = {0, 1, 3, 2};
  for (int k = 0; k < 4; ++k) {
    writes[k].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    writes[k].dstSet = r.set;
    writes[k].dstBinding = binding_of[k];
    writes[k].descriptorCount = 1;
    if (k < 3) {
      writes[k].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[k].pBufferInfo = &infos[k];
    } else {
      writes[k].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
      writes[k].pImageInfo = &image_info;
    }
  }
  vkUpdateDescriptorSets(dev, 4, writes, 0, nullptr);

  const std::array<float, 4> bg = premultiplied(style.background);
  VkClearValue clear{};
  std::memcpy(clear.color.float32, bg.data(), sizeof(float) * 4);
  VkRenderPassBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
  begin.renderPass = r.render_pass.get();
  begin.framebuffer = r.framebuffer.get();
  begin.renderArea = {{0, 0}, {w, h}};
  begin.clearValueCount = 1;
  begin.pClearValues = &clear;
  vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, r.layout.get(), 0, 1, &r.set, 0, nullptr);

  if (!compute && style.uncertified && border_px > 0) {
    VkClearAttachment red{};
    red.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    red.colorAttachment = 0;
    std::memcpy(red.clearValue.color.float32, kBorderRed, sizeof kBorderRed);
    const uint32_t b = border_px;
    const VkClearRect rects[4] = {{{{0, 0}, {w, b}}, 0, 1},
                                  {{{0, static_cast<int32_t>(h - b)}, {w, b}}, 0, 1},
                                  {{{0, static_cast<int32_t>(b)}, {b, h - 2 * b}}, 0, 1},
                                  {{{static_cast<int32_t>(w - b), static_cast<int32_t>(b)}, {b, h - 2 * b}}, 0, 1}};
    vkCmdClearAttachments(cmd, 1, &red, h > 2 * b ? 4 : 2, rects);
  }

  if (!compute) {  // the shape
    // Drawn without blending: each sample keeps the last triangle in mesh order that
    // covers it (Vulkan's primitive order), its colour composited over the background
    // by render_mesh.frag, as raster_resolve.comp does with the visibility buffer. So
    // where a map overlaps itself both rasterizers show the top layer alone, whatever
    // its alpha, and never the layers blended (issue #20).
    std::memcpy(pc.color, style.fill.data(), sizeof pc.color);
    std::memcpy(pc.background, bg.data(), sizeof pc.background);
    std::memcpy(pc.border_color, kBorderRed, sizeof pc.border_color);
    pc.first = style.uncertified ? border_px : 0u;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, r.mesh.get());
    vkCmdPushConstants(cmd, r.layout.get(), kPushStages, 0, sizeof pc, &pc);
    const VkDeviceSize zero = 0;
    const VkBuffer uv = r.uv.handle();
    vkCmdBindVertexBuffers(cmd, 0, 1, &uv, &zero);
    vkCmdBindIndexBuffer(cmd, r.index.handle(), 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, static_cast<uint32_t>(index_count_), 1, 0, 0, 0);
  }

  if (lines) {
    std::memcpy(pc.color, style.boundary_color.data(), sizeof pc.color);
    pc.size_px = style.boundary_width_px;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, r.line.get());
    vkCmdPushConstants(cmd, r.layout.get(), kPushStages, 0, sizeof pc, &pc);
    vkCmdDraw(cmd, 6, static_cast<uint32_t>(segment_count_), 0, 0);
  }
  if (discs) {
    std::memcpy(pc.color, style.handle_color.data(), sizeof pc.color);
    std::memcpy(pc.color2, style.handle_outline.data(), sizeof pc.color2);
    pc.size_px = style.handle_radius_px;
    pc.size2_px = std::clamp(style.handle_outline_px, 0.0f, style.handle_radius_px);
    pc.first = static_cast<uint32_t>(vertex_count_);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, r.disc.get());
    vkCmdPushConstants(cmd, r.layout.get(), kPushStages, 0, sizeof pc, &pc);
    vkCmdDraw(cmd, 6, static_cast<uint32_t>(handles), 0, 0);
  }
  vkCmdEndRenderPass(cmd);
  drawn_ = true;
  if (copy_out) record_copy_out(cmd);
  stats_.upload_ms = ms_since(t0);
}

void Renderer::record_compute_raster(VkCommandBuffer cmd, const Buffer& f, const Buffer& fields, const View& view,
                                     const RenderStyle& style, uint32_t border_px) {
  Impl& r = *impl_;
  const RenderPush g = frame_push(view, style, width_, height_, has_texture_);
  for (DescriptorSet* set : {&r.raster_set, &r.resolve_set}) {
    set->bind(0, f);
    set->bind(1, fields);
    set->bind(2, (has_texture_ ? r.texture : r.white).view.get(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, r.sampler.get());
    set->bind(3, r.index);
    set->bind(4, r.uv);
    set->bind(5, r.vis);
    set->bind(6, r.large);
    set->bind(7, r.resolve.view.get(), VK_IMAGE_LAYOUT_GENERAL);
  }
  RasterPush pc{};
  const std::array<float, 4> bg = premultiplied(style.background);
  std::memcpy(pc.background, bg.data(), sizeof pc.background);
  std::memcpy(pc.border_color, kBorderRed, sizeof pc.border_color);
  std::memcpy(pc.fill, style.fill.data(), sizeof pc.fill);
  std::memcpy(pc.scale, g.scale, sizeof pc.scale);
  std::memcpy(pc.offset, g.offset, sizeof pc.offset);
  pc.width = static_cast<uint32_t>(width_);
  pc.height = static_cast<uint32_t>(height_);
  pc.samples = static_cast<uint32_t>(samples_);
  pc.triangles = static_cast<uint32_t>(index_count_ / 3);
  pc.dist_lo = g.dist_lo;
  pc.dist_inv = g.dist_inv;
  pc.overlay_alpha = g.overlay_alpha;
  pc.flags = g.flags;
  pc.border_px = border_px;

  // The previous frame's passes (and its lines, discs and copy out of the image) before
  // this frame rewrites the visibility buffer, the queue and the image.
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                 VK_ACCESS_TRANSFER_WRITE_BIT);
  vkCmdFillBuffer(cmd, r.vis.handle(), 0, VK_WHOLE_SIZE, 0);
  vkCmdFillBuffer(cmd, r.large.handle(), 0, sizeof(uint32_t), 0);  // none queued
  memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  // From UNDEFINED: every pixel is rewritten.
  image_barrier(cmd, r.resolve.image.get(), VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);

  // Triangles into the visibility buffer: pass 0 kRasterLanes invocations per triangle,
  // pass 1 the large ones pass 0 queued, a workgroup each in turn (a fixed dispatch,
  // not an indirect one: most frames queue none, and its groups then return at once).
  r.raster.bind(cmd, r.raster_set);
  pc.pass = 0;
  r.raster.push(cmd, &pc, sizeof pc);
  const auto [gx, gy] = split_dispatch(*context_, (uint64_t{pc.triangles} * kRasterLanes + 63) / 64);
  vkCmdDispatch(cmd, gx, gy, 1);
  constexpr VkAccessFlags kReadWrite = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 kReadWrite);
  pc.pass = 1;
  r.raster.push(cmd, &pc, sizeof pc);
  vkCmdDispatch(cmd, std::min(pc.triangles, 1024u), 1, 1);
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 kReadWrite);

  // Shade, blend over the background, average the samples, write the image.
  r.resolve_pass.bind(cmd, r.resolve_set);
  r.resolve_pass.push(cmd, &pc, sizeof pc);
  vkCmdDispatch(cmd, (pc.width + 7) / 8, (pc.height + 7) / 8, 1);
}

void Renderer::record_copy_out(VkCommandBuffer cmd) {
  // The render pass's dependency to VK_SUBPASS_EXTERNAL (or, with nothing drawn over a compute-rasterized
  // image, its layout barrier) orders the image's writes before this.
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {static_cast<uint32_t>(width_), static_cast<uint32_t>(height_), 1};
  vkCmdCopyImageToBuffer(cmd, impl_->resolve.image.get(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                         impl_->readback.handle(), 1, &copy);
  memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                 VK_ACCESS_HOST_READ_BIT);
}

RgbaImage Renderer::read_frame() {
  if (!drawn_) throw InputError("renderer: no frame drawn yet (draw, record or render first)");
  context_->submit_and_wait([&](VkCommandBuffer cmd) { record_copy_out(cmd); });
  return read_image();
}

}  // namespace hsi::vk
