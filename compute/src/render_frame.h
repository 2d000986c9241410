// What the renderer's passes share (private to renderer*.cpp and raster_*.cpp): the
// push constants the shaders read, the buffers and texture a frame draws from, and
// the colour conventions (premultiplied throughout; RGBA8 targets).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "hsi/compute/renderer.h"

namespace hsi::compute::render {

constexpr VkFormat kColorFormat = VK_FORMAT_R8G8B8A8_UNORM;

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
constexpr VkShaderStageFlags kPushStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
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

inline std::array<float, 4> premultiplied(const std::array<float, 4>& c) { return {c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]}; }

// What a frame's passes share: the view (world -> pixels), the colour map and the
// shape's flags; the rest is per draw.
inline RenderPush frame_push(const View& view, const RenderStyle& style, int width, int height, bool textured) {
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

// The buffers and texture one frame is drawn from: positions f and distortion fields
// in the dense evaluation's layout (evaluated or given), the mesh (triangle indices,
// texture coordinates, boundary segments) and the texture with its sampler.
struct FrameInputs {
  const Buffer* f = nullptr;
  const Buffer* fields = nullptr;
  const Buffer* index = nullptr;
  const Buffer* uv = nullptr;
  const Buffer* segments = nullptr;
  VkImageView texture = VK_NULL_HANDLE;
  VkSampler sampler = VK_NULL_HANDLE;
  uint32_t index_count = 0, segment_count = 0;
  uint32_t vertex_count = 0, handle_count = 0;  // handles: drawn as discs from f[vertex_count]
};

}  // namespace hsi::compute::render
