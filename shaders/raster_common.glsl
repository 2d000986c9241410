// Shared by the compute rasterizer's two passes (raster.comp: triangles -> the
// visibility buffer; raster_resolve.comp: visibility buffer -> shaded, resolved
// pixels). Host side: compute/src/renderer.cpp, whose `RasterPush` mirrors Push
// below. Positions come straight from the dense evaluation's output (f at the mesh
// vertices) in its precision (HSI_REAL_DOUBLE), mapped to pixels exactly as the
// graphics path's vertex shaders map them (render_common.glsl).
#ifndef HSI_RASTER_COMMON_GLSL
#define HSI_RASTER_COMMON_GLSL

#include "hsi_real.glsl"
#include "render_shade.glsl"

layout(push_constant) uniform Push {
  vec4 background;    // premultiplied: where no triangle covers a sample
  vec4 border_color;  // premultiplied: the uncertified frame's border (border_px > 0)
  vec4 fill;          // straight: the shape's colour without a texture
  vec2 scale;         // world -> pixel: px = world * scale + offset (scale.y < 0: y up)
  vec2 offset;
  uint width, height;
  uint samples;       // per pixel: 1, 2, 4 or 8, at Vulkan's standard sample locations
  uint triangles;
  float dist_lo, dist_inv, overlay_alpha;
  uint flags;         // kTextured | kDistortion | kUncertified (render_shade.glsl)
  uint border_px;
  uint pass;          // raster.comp: 0 a few invocations per triangle, 1 workgroups over the large triangles
} pc;

layout(std430, set = 0, binding = 0) readonly buffer F { Real2 f[]; };
layout(std430, set = 0, binding = 1) readonly buffer Fields { Real4 fields[]; };  // sigma1, sigma2, kappa, E_SD
layout(set = 0, binding = 2) uniform sampler2D tex;
layout(std430, set = 0, binding = 3) readonly buffer Triangles { uint tri[]; };  // 3 vertex indices each
layout(std430, set = 0, binding = 4) readonly buffer Uv { vec2 uv[]; };          // texture coordinates per vertex
// Per sample (pixel-major: (y * width + x) * samples + k): 1 + the index of the
// last triangle covering it in drawing order (atomicMax), 0 for none.
layout(std430, set = 0, binding = 5) buffer Visibility { uint vis[]; };
// Triangles too large for one invocation: how many raster.comp's pass 0 queued, then
// their indices.
layout(std430, set = 0, binding = 6) buffer Large { uint large_count; uint large[]; };
layout(set = 0, binding = 7, rgba8) uniform writeonly image2D out_image;

// Pixel position (x right, y down from the top-left corner) of f[i]: render_common.glsl's pixel_of.
vec2 pixel_of(uint i) {
  const Real2 p = f[i] * Real2(pc.scale) + Real2(pc.offset);
  return vec2(p);
}

// Vulkan's standard sample locations (in the pixel, from its top-left corner).
vec2 sample_location(uint samples, uint k) {
  if (samples == 1u) return vec2(0.5);
  if (samples == 2u) return k == 0u ? vec2(0.75) : vec2(0.25);
  if (samples == 4u) {
    const vec2 s4[4] = vec2[4](vec2(0.375, 0.125), vec2(0.875, 0.375), vec2(0.125, 0.625), vec2(0.625, 0.875));
    return s4[k];
  }
  const vec2 s8[8] = vec2[8](vec2(0.5625, 0.3125), vec2(0.4375, 0.6875), vec2(0.8125, 0.5625), vec2(0.3125, 0.1875),
                             vec2(0.1875, 0.8125), vec2(0.0625, 0.4375), vec2(0.6875, 0.9375), vec2(0.9375, 0.0625));
  return s8[k];
}

#endif  // HSI_RASTER_COMMON_GLSL
