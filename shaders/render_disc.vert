// Handles as discs at f(handle): one instance per handle, a screen-space square of
// 6 vertices around it (1 px larger than the disc, for the coverage ramp).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) out vec2 local_px;  // offset from the disc's centre, in pixels

void main() {
  const vec2 c = pixel_of(pc.first + uint(gl_InstanceIndex));
  const int v = gl_VertexIndex;  // triangles (00, 10, 01), (01, 10, 11)
  const vec2 corner = vec2((v == 1 || v == 4 || v == 5) ? 1.0 : -1.0, (v == 2 || v == 3 || v == 5) ? 1.0 : -1.0);
  local_px = corner * (pc.size_px + 1.0);
  gl_Position = ndc_of(c + local_px);
}
