// The viewer's UI (Dear ImGui draw lists, viewer/src/ui_renderer.cpp): positions in
// window points, mapped to clip space by a scale and an offset; colours straight RGBA.
#version 460

layout(push_constant) uniform Push {
  vec2 scale;
  vec2 offset;
} pc;

layout(location = 0) in vec2 in_pos;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;
layout(location = 0) out vec2 uv;
layout(location = 1) out vec4 color;

void main() {
  uv = in_uv;
  color = in_color;
  gl_Position = vec4(in_pos * pc.scale + pc.offset, 0.0, 1.0);
}
