// A filled disc of radius size_px with an outline of width size2_px, anti-aliased
// by analytic coverage.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) in vec2 local_px;
layout(location = 0) out vec4 out_color;

void main() {
  const float d = length(local_px);
  const float coverage = clamp(pc.size_px + 0.5 - d, 0.0, 1.0);
  const float outline = clamp(d - (pc.size_px - pc.size2_px) + 0.5, 0.0, 1.0);
  const vec4 c = mix(pc.color, pc.color2, outline);
  const float a = c.a * coverage;
  out_color = vec4(c.rgb * a, a);
}
