// Texture (premultiplied RGBA) or flat fill, optionally under the distortion colour
// map and a red tint for an uncertified frame; writes premultiplied colour.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(set = 0, binding = 2) uniform sampler2D tex;
layout(location = 0) in vec2 uv;
layout(location = 1) in float kappa_t;
layout(location = 0) out vec4 out_color;

void main() {
  vec4 c = (pc.flags & kTextured) != 0u ? texture(tex, uv) : vec4(pc.color.rgb * pc.color.a, pc.color.a);
  if ((pc.flags & kDistortion) != 0u) c = mix(c, vec4(hsi_colormap(kappa_t), 1.0), pc.overlay_alpha);
  if ((pc.flags & kUncertified) != 0u) c.rgb = mix(c.rgb, vec3(0.92, 0.04, 0.04) * c.a, 0.55);
  out_color = c;
}
