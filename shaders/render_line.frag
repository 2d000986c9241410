#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) in float side_px;
layout(location = 0) out vec4 out_color;

void main() {
  const float coverage = clamp(0.5 * pc.size_px + 0.5 - abs(side_px), 0.0, 1.0);
  const float a = pc.color.a * coverage;
  out_color = vec4(pc.color.rgb * a, a);
}
