// The renderer's compute rasterizer (see raster_compute.h and shaders/raster*.comp).
#include "raster_compute.h"

#include <cstring>
#include <span>

#include "hsi/compute/spirv/raster_f32.h"
#include "hsi/compute/spirv/raster_f64.h"
#include "hsi/compute/spirv/raster_resolve_f32.h"
#include "hsi/compute/spirv/raster_resolve_f64.h"

namespace hsi::compute::render {

namespace {
// Bindings of shaders/raster_common.glsl.
constexpr VkDescriptorType kSb = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
constexpr VkDescriptorType kBindings[8] = {kSb, kSb, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kSb, kSb, kSb, kSb,
                                           VK_DESCRIPTOR_TYPE_STORAGE_IMAGE};
using S = std::span<const uint32_t>;
}  // namespace

ComputeRaster::ComputeRaster(const Context& context, uint32_t width, uint32_t height, uint32_t samples, bool f64)
    : context_(&context), width_(width), height_(height), samples_(samples),
      vis_(context, visibility_bytes(width, height, samples), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
           MemoryUse::kDeviceLocal),
      raster_(context, f64 ? S(raster_f64) : S(raster_f32), kBindings, sizeof(RasterPush)),
      resolve_(context, f64 ? S(raster_resolve_f64) : S(raster_resolve_f32), kBindings, sizeof(RasterPush)),
      raster_set_(context, raster_.layout()),
      resolve_set_(context, resolve_.layout()) {}

void ComputeRaster::set_triangles(size_t triangles) {
  large_ = Buffer(*context_, (1 + triangles) * sizeof(uint32_t),
                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kDeviceLocal);
}

void ComputeRaster::record(VkCommandBuffer cmd, const FrameInputs& in, const Image& target, const RenderStyle& style,
                           const RenderPush& g, uint32_t border_px) {
  for (DescriptorSet* set : {&raster_set_, &resolve_set_}) {
    set->bind(0, *in.f);
    set->bind(1, *in.fields);
    set->bind(2, in.texture, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, in.sampler);
    set->bind(3, *in.index);
    set->bind(4, *in.uv);
    set->bind(5, vis_);
    set->bind(6, large_);
    set->bind(7, target.view(), VK_IMAGE_LAYOUT_GENERAL);
  }
  RasterPush pc{};
  const std::array<float, 4> bg = premultiplied(style.background);
  std::memcpy(pc.background, bg.data(), sizeof pc.background);
  std::memcpy(pc.border_color, kBorderRed, sizeof pc.border_color);
  std::memcpy(pc.fill, style.fill.data(), sizeof pc.fill);
  std::memcpy(pc.scale, g.scale, sizeof pc.scale);
  std::memcpy(pc.offset, g.offset, sizeof pc.offset);
  pc.width = width_;
  pc.height = height_;
  pc.samples = samples_;
  pc.triangles = in.index_count / 3;
  pc.dist_lo = g.dist_lo;
  pc.dist_inv = g.dist_inv;
  pc.overlay_alpha = g.overlay_alpha;
  pc.flags = g.flags;
  pc.border_px = border_px;

  // The previous frame's passes (and its lines, discs and copy out of the image) before
  // this frame rewrites the visibility buffer, the queue and the image.
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                 VK_ACCESS_TRANSFER_WRITE_BIT);
  vkCmdFillBuffer(cmd, vis_.handle(), 0, VK_WHOLE_SIZE, 0);
  vkCmdFillBuffer(cmd, large_.handle(), 0, sizeof(uint32_t), 0);  // none queued
  memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  // From UNDEFINED: every pixel is rewritten.
  image_barrier(cmd, target.handle(), VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);

  // Triangles into the visibility buffer: pass 0 kRasterLanes invocations per triangle,
  // pass 1 the large ones pass 0 queued, a workgroup each in turn (a fixed dispatch,
  // not an indirect one: most frames queue none, and its groups then return at once).
  raster_.bind(cmd, raster_set_);
  pc.pass = 0;
  raster_.push(cmd, &pc, sizeof pc);
  const auto [gx, gy] = split_dispatch(*context_, (uint64_t{pc.triangles} * kRasterLanes + 63) / 64);
  vkCmdDispatch(cmd, gx, gy, 1);
  constexpr VkAccessFlags kReadWrite = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 kReadWrite);
  pc.pass = 1;
  raster_.push(cmd, &pc, sizeof pc);
  vkCmdDispatch(cmd, std::min(pc.triangles, 1024u), 1, 1);
  memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 kReadWrite);

  // Shade, blend over the background, average the samples, write the image.
  resolve_.bind(cmd, resolve_set_);
  resolve_.push(cmd, &pc, sizeof pc);
  vkCmdDispatch(cmd, (pc.width + 7) / 8, (pc.height + 7) / 8, 1);
}

}  // namespace hsi::compute::render
