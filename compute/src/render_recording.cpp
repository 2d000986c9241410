// Recording a frame of the offscreen renderer (see renderer.h): the mesh evaluation
// on the GPU, then the chosen rasterizer's passes into the target image, and the copy
// of that image to the host (un-premultiplied into an RgbaImage).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "hsi/compute/renderer.h"
#include "renderer_impl.h"
#include "timing.h"

namespace hsi::compute {

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

void Renderer::record(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, const View& view,
                      const RenderStyle& style, bool mark_evaluation) {
  check_frame(view, style);
  stats_ = {};
  record_frame(cmd, &cage, &map, handle_count_, view, style, false, mark_evaluation);
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
  const render::RenderPush pc = render::frame_push(view, style, width_, height_, has_texture_);
  const float border = style.border_px > 0 ? style.border_px : std::max(4.0f, static_cast<float>(std::min(width_, height_)) / 64);
  const uint32_t border_px = std::min(static_cast<uint32_t>(std::lround(border)), static_cast<uint32_t>(std::min(width_, height_) / 2));

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

  render::FrameInputs in;
  in.f = cage ? &eval_.device_output(0) : &r.given_f;
  in.fields = cage ? &eval_.device_output(3) : &r.given_fields;
  in.index = &r.index;
  in.uv = &r.uv;
  in.segments = &r.segments;
  in.texture = (has_texture_ ? r.texture : r.white).view();
  in.sampler = r.sampler.handle();
  in.index_count = static_cast<uint32_t>(index_count_);
  in.segment_count = static_cast<uint32_t>(segment_count_);
  in.vertex_count = static_cast<uint32_t>(vertex_count_);
  in.handle_count = static_cast<uint32_t>(handles);
  const bool lines = (style.overlays & kOverlayBoundary) && segment_count_ > 0 && style.boundary_width_px > 0;
  const bool discs = (style.overlays & kOverlayHandles) && handles > 0 && style.handle_radius_px > 0;
  if (r.compute) {
    r.compute->record(cmd, in, r.target, style, pc, style.uncertified ? border_px : 0u);
    if (!lines && !discs) {  // nothing to draw over it: no render pass, just the layout the copy out expects
      image_barrier(cmd, r.target.handle(), VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                    VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT);
      drawn_ = true;
      if (copy_out) record_copy_out(cmd);
      stats_.upload_ms = ms_since(t0);
      return;
    }
  }
  r.graphics->record(cmd, in, style, pc, border_px, lines, discs);
  drawn_ = true;
  if (copy_out) record_copy_out(cmd);
  stats_.upload_ms = ms_since(t0);
}

void Renderer::record_copy_out(VkCommandBuffer cmd) {
  // The render pass's dependency to VK_SUBPASS_EXTERNAL (or, with nothing drawn over a compute-rasterized
  // image, its layout barrier) orders the image's writes before this.
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {static_cast<uint32_t>(width_), static_cast<uint32_t>(height_), 1};
  vkCmdCopyImageToBuffer(cmd, impl_->target.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                         impl_->readback.handle(), 1, &copy);
  memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                 VK_ACCESS_HOST_READ_BIT);
}

RgbaImage Renderer::read_frame() {
  if (!drawn_) throw InputError("renderer: no frame drawn yet (draw, record or render first)");
  context_->submit_and_wait([&](VkCommandBuffer cmd) { record_copy_out(cmd); });
  return read_image();
}

}  // namespace hsi::compute
