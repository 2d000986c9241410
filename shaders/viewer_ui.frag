// The viewer's UI: vertex colour times the bound texture (the font atlas, or the
// rendered frame), straight alpha (blended src_alpha, one_minus_src_alpha).
#version 460

layout(set = 0, binding = 0) uniform sampler2D tex;
layout(location = 0) in vec2 uv;
layout(location = 1) in vec4 color;
layout(location = 0) out vec4 out_color;

void main() { out_color = color * texture(tex, uv); }
