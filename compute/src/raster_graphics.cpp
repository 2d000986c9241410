// The renderer's graphics passes (see raster_graphics.h and shaders/render_*).
// Colours are premultiplied: the clear colour, the texture and the "over" blending.
#include "raster_graphics.h"

#include <cstring>
#include <span>
#include <vector>

#include "hsi/compute/spirv/render_disc_frag.h"
#include "hsi/compute/spirv/render_disc_vert_f32.h"
#include "hsi/compute/spirv/render_disc_vert_f64.h"
#include "hsi/compute/spirv/render_line_frag.h"
#include "hsi/compute/spirv/render_line_vert_f32.h"
#include "hsi/compute/spirv/render_line_vert_f64.h"
#include "hsi/compute/spirv/render_mesh_frag.h"
#include "hsi/compute/spirv/render_mesh_vert_f32.h"
#include "hsi/compute/spirv/render_mesh_vert_f64.h"

namespace hsi::compute::render {

namespace {

// The colour attachment: the graphics rasterizer clears an MSAA image (or the target,
// single-sampled) and resolves it into the target; after the compute rasterizer the
// target is loaded as its compute passes left it (GENERAL), once they have written it.
RenderPassInfo pass_info(VkSampleCountFlagBits samples, bool after_compute) {
  const bool msaa = samples != VK_SAMPLE_COUNT_1_BIT;
  RenderPassInfo info;
  info.color.format = kColorFormat;
  info.color.samples = samples;
  info.color.load = after_compute ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR;
  info.color.store = msaa ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
  info.color.initial_layout = after_compute ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_UNDEFINED;
  info.color.final_layout = msaa ? VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  info.resolve = msaa;
  // The previous frame's copy out of the image (a read) before this frame's writes;
  // after the compute rasterizer, its writes of the image before the lines and discs
  // blend onto it. The rendered image before the copy to the host (the defaults).
  if (after_compute) {
    info.wait_stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    info.wait_access = VK_ACCESS_SHADER_WRITE_BIT;
  }
  return info;
}

// Bindings of shaders/render_common.glsl: f, fields (the evaluation's outputs), the
// texture, the boundary segments.
constexpr Binding kBindings[4] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_VERTEX_BIT},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_VERTEX_BIT},
                                  {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_VERTEX_BIT}};

}  // namespace

GraphicsRaster::GraphicsRaster(const Context& context, const Image& target, VkSampleCountFlagBits samples,
                               bool after_compute, bool f64)
    : after_compute_(after_compute),
      pass_(context, pass_info(samples, after_compute)),
      layout_(context, kBindings, kPushStages, sizeof(RenderPush)),
      set_(context, layout_) {
  const uint32_t w = target.info().width, h = target.info().height;
  std::vector<VkImageView> views = {target.view()};
  if (samples != VK_SAMPLE_COUNT_1_BIT) {
    ImageInfo info;
    info.width = w;
    info.height = h;
    info.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT;
    info.samples = samples;
    info.preferred_memory = VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT;
    msaa_ = Image(context, info);
    views = {msaa_.view(), target.view()};
  }
  framebuffer_ = Framebuffer(context, pass_, views, {w, h});

  PipelineState state;
  state.samples = samples;
  state.viewport = {w, h};
  using S = std::span<const uint32_t>;
  if (!after_compute) {
    // Drawn without blending (see record); texture coordinates per vertex.
    PipelineState mesh = state;
    mesh.vertex_input.bindings = {{0, 2 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX}};
    mesh.vertex_input.attributes = {{0, 0, VK_FORMAT_R32G32_SFLOAT, 0}};
    mesh_ = GraphicsPipeline(context, layout_, pass_, f64 ? S(render_mesh_vert_f64) : S(render_mesh_vert_f32),
                             S(render_mesh_frag), mesh);
  }
  state.blend.enable = true;  // premultiplied "over"
  line_ = GraphicsPipeline(context, layout_, pass_, f64 ? S(render_line_vert_f64) : S(render_line_vert_f32),
                           S(render_line_frag), state);
  disc_ = GraphicsPipeline(context, layout_, pass_, f64 ? S(render_disc_vert_f64) : S(render_disc_vert_f32),
                           S(render_disc_frag), state);
}

void GraphicsRaster::record(VkCommandBuffer cmd, const FrameInputs& in, const RenderStyle& style, RenderPush pc,
                            uint32_t border_px, bool lines, bool discs) {
  // The set is not bound in any pending command buffer: point it at this frame's buffers.
  set_.bind(0, *in.f);
  set_.bind(1, *in.fields);
  set_.bind(2, in.texture, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, in.sampler);
  set_.bind(3, *in.segments);

  const std::array<float, 4> bg = premultiplied(style.background);
  pass_.begin(cmd, framebuffer_, bg);
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, set_);
  const VkExtent2D extent = framebuffer_.extent();
  const uint32_t w = extent.width, h = extent.height;

  if (!after_compute_ && style.uncertified && border_px > 0) {
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

  if (!after_compute_) {  // the shape
    // Drawn without blending: each sample keeps the last triangle in mesh order that
    // covers it (Vulkan's primitive order), its colour composited over the background
    // by render_mesh.frag, as raster_resolve.comp does with the visibility buffer. So
    // where a map overlaps itself both rasterizers show the top layer alone, whatever
    // its alpha, and never the layers blended (issue #20).
    std::memcpy(pc.color, style.fill.data(), sizeof pc.color);
    std::memcpy(pc.background, bg.data(), sizeof pc.background);
    std::memcpy(pc.border_color, kBorderRed, sizeof pc.border_color);
    pc.first = style.uncertified ? border_px : 0u;
    mesh_.bind(cmd);
    layout_.push(cmd, &pc, sizeof pc);
    const VkDeviceSize zero = 0;
    const VkBuffer uv = in.uv->handle();
    vkCmdBindVertexBuffers(cmd, 0, 1, &uv, &zero);
    vkCmdBindIndexBuffer(cmd, in.index->handle(), 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, in.index_count, 1, 0, 0, 0);
  }
  if (lines) {
    std::memcpy(pc.color, style.boundary_color.data(), sizeof pc.color);
    pc.size_px = style.boundary_width_px;
    line_.bind(cmd);
    layout_.push(cmd, &pc, sizeof pc);
    vkCmdDraw(cmd, 6, in.segment_count, 0, 0);
  }
  if (discs) {
    std::memcpy(pc.color, style.handle_color.data(), sizeof pc.color);
    std::memcpy(pc.color2, style.handle_outline.data(), sizeof pc.color2);
    pc.size_px = style.handle_radius_px;
    pc.size2_px = std::clamp(style.handle_outline_px, 0.0f, style.handle_radius_px);
    pc.first = in.vertex_count;
    disc_.bind(cmd);
    layout_.push(cmd, &pc, sizeof pc);
    vkCmdDraw(cmd, 6, in.handle_count, 0, 0);
  }
  vkCmdEndRenderPass(cmd);
}

}  // namespace hsi::compute::render
