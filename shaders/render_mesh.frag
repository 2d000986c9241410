// Texture (premultiplied RGBA) or flat fill, optionally under the distortion colour
// map and a red tint for an uncertified frame (render_shade.glsl), composited over the
// background (or the uncertified frame's border) here: the mesh is drawn without
// blending, so where the map overlaps itself a sample keeps the last triangle in mesh
// order alone, as the compute rasterizer's visibility buffer does (raster_resolve.comp);
// writes premultiplied colour.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(set = 0, binding = 2) uniform sampler2D tex;
layout(location = 0) in vec2 uv;
layout(location = 1) in float kappa_t;
layout(location = 0) out vec4 out_color;

void main() {
  const vec4 base = (pc.flags & kTextured) != 0u ? texture(tex, uv) : pc.color;
  const vec4 c = hsi_shade(base, kappa_t, pc.flags, pc.overlay_alpha);
  // gl_FragCoord.xy is the pixel's centre (x + 0.5, y + 0.5): raster_resolve.comp's border test.
  const float b = float(pc.first);
  const vec2 p = gl_FragCoord.xy;
  const bool in_border = pc.first > 0u && (p.x < b || p.y < b || p.x >= pc.viewport.x - b || p.y >= pc.viewport.y - b);
  out_color = c + (1.0 - c.a) * (in_border ? pc.border_color : pc.background);
}
