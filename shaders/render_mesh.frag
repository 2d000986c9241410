// Texture (premultiplied RGBA) or flat fill, optionally under the distortion colour
// map and a red tint for an uncertified frame (render_shade.glsl); writes premultiplied colour.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(set = 0, binding = 2) uniform sampler2D tex;
layout(location = 0) in vec2 uv;
layout(location = 1) in float kappa_t;
layout(location = 0) out vec4 out_color;

void main() {
  const vec4 base = (pc.flags & kTextured) != 0u ? texture(tex, uv) : pc.color;
  out_color = hsi_shade(base, kappa_t, pc.flags, pc.overlay_alpha);
}
