// Boundary segments as screen-space quads, one instance per segment (a, b) of
// `segments`, 6 vertices each; the quad is 1 px wider on each side than the line
// and extends half a width past each end, so joints close and edges are smoothed
// by coverage in the fragment shader (on top of MSAA).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) out float side_px;  // signed distance from the centre line, in pixels

void main() {
  const uvec2 s = segments[gl_InstanceIndex];
  const vec2 a = pixel_of(s.x), b = pixel_of(s.y);
  const vec2 d = b - a;
  const float len = length(d);
  const vec2 t = len > 1e-6 ? d / len : vec2(1.0, 0.0);
  const vec2 n = vec2(-t.y, t.x);
  const float half_width = 0.5 * pc.size_px, reach = half_width + 1.0;
  const int v = gl_VertexIndex;  // triangles (a-, b-, a+), (a+, b-, b+)
  const bool at_b = v == 1 || v == 4 || v == 5;
  const float side = (v == 2 || v == 3 || v == 5) ? 1.0 : -1.0;
  const vec2 p = (at_b ? b + t * half_width : a - t * half_width) + n * side * reach;
  side_px = side * reach;
  gl_Position = ndc_of(p);
}
