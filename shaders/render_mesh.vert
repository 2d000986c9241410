// The deformed mesh: vertex i sits at f(rest vertex i), read from the dense
// evaluation's output; its texture coordinate is the rest position in the texture's
// rectangle; its colour-map parameter comes from the conformal distortion sigma1/sigma2.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec2 uv;
layout(location = 1) out float kappa_t;  // unclamped; the fragment shader clamps after interpolation

void main() {
  const uint i = uint(gl_VertexIndex);
  gl_Position = ndc_of(pixel_of(i));
  uv = in_uv;
  kappa_t = hsi_kappa_t(float(fields[i].z), pc.dist_lo, pc.dist_inv);
}
