// Shared by the render_* shaders (offscreen rendering of a deformed shape; host side
// compute/src/renderer.cpp, whose `RenderPush` mirrors Push below). Positions come
// straight from the dense evaluation's output buffer (f at the mesh vertices, then
// at the handles) in the evaluation's precision (HSI_REAL_DOUBLE: double or float),
// so no vertex data goes through the host between evaluating and drawing.
#ifndef HSI_RENDER_COMMON_GLSL
#define HSI_RENDER_COMMON_GLSL

#include "hsi_real.glsl"
#include "render_shade.glsl"

layout(push_constant) uniform Push {
  vec4 color;           // straight RGBA: flat fill (mesh), line colour, disc fill
  vec4 color2;          // disc outline
  vec2 scale;           // world -> pixel: px = world * scale + offset (scale.y < 0: y up)
  vec2 offset;
  vec2 viewport;        // image size in pixels
  float size_px;        // line width, disc radius
  float size2_px;       // disc outline width
  float dist_lo;        // colour map: t = (kappa - dist_lo) * dist_inv
  float dist_inv;
  float overlay_alpha;  // opacity of the colour map over the texture
  uint flags;
  uint first;           // index in f of the first handle (discs); the mesh: the border's width in pixels (0: none)
  vec4 background;      // the mesh: premultiplied background, which the top layer is composited over
  vec4 border_color;    // the mesh: premultiplied colour of the uncertified frame's border
} pc;

#ifdef HSI_REAL_DOUBLE
layout(std430, set = 0, binding = 0) readonly buffer F { Real2 f[]; };
layout(std430, set = 0, binding = 1) readonly buffer Fields { Real4 fields[]; };  // sigma1, sigma2, kappa, E_SD
layout(std430, set = 0, binding = 3) readonly buffer Segments { uvec2 segments[]; };

// Pixel position (x right, y down from the top-left corner) of f[i].
vec2 pixel_of(uint i) {
  const Real2 p = f[i] * Real2(pc.scale) + Real2(pc.offset);
  return vec2(p);
}
#endif

vec4 ndc_of(vec2 px) { return vec4(px / pc.viewport * 2.0 - 1.0, 0.0, 1.0); }

#endif  // HSI_RENDER_COMMON_GLSL
