// GPU playback of a baked sequence (.hsib, hsi/baked_runtime.h): one source for
// Vulkan, OpenGL and WebGL2. The application writes its version line, then one
// preamble (hsib_preamble_vulkan.glsl, or hsib_preamble_gl.glsl for OpenGL 3.3+ and
// WebGL2), then this file, then its own shader, which calls hsib_position(vertex).
//
// Data, both laid out by the C runtime so that the layout is decided in one place:
//   rows      per vertex, its R basis rows as ceil(R/4) RGBA32F texels (4 rows each,
//             zero-padded): texel v*T + q holds rows 4q..4q+3 of vertex v. Filled
//             once per mesh by hsib_gpu_rows (a texture of hsib_gpu_texture_width()
//             texels a line, or a storage buffer of vec4 under Vulkan).
//   uniforms  per draw, hsib_gpu_uniforms: the two frames' translations, the blend
//             parameter s, and per row the two frames' weights (std140-compatible).
// The position is mix(rows·W0 + c0, rows·W1 + c1, s): the blend of two frames
// (hsib_blend_at_time decides which and whether that blend was certified).
#ifndef HSIB_MAX_ROWS
#define HSIB_MAX_ROWS 224  // R of the sequences drawn; 224 + 2 vec4 fit WebGL2's minimum of 256
#endif

HSIB_BEGIN_UNIFORMS
HSIB_UNIFORM vec4 hsib_pose;    // (c0.x, c0.y, c1.x, c1.y): the two frames' translations
HSIB_UNIFORM vec4 hsib_params;  // (s, R, T = texels per vertex, 0)
HSIB_UNIFORM vec4 hsib_weights[HSIB_MAX_ROWS];  // row k: (w0.x, w0.y, w1.x, w1.y)
HSIB_END_UNIFORMS

// The blended, deformed position of vertex `vertex` (its index in the bound mesh).
vec2 hsib_position(int vertex) {
  int texels = int(hsib_params.z);
  vec4 acc = vec4(0.0);  // (x in frame 0, y in frame 0, x in frame 1, y in frame 1)
  for (int q = 0; q < texels; ++q) {
    vec4 r = HSIB_ROW_TEXEL(vertex * texels + q);
    int k = 4 * q;
    acc += r.x * hsib_weights[k] + r.y * hsib_weights[k + 1] + r.z * hsib_weights[k + 2] + r.w * hsib_weights[k + 3];
  }
  return mix(acc.xy + hsib_pose.xy, acc.zw + hsib_pose.zw, hsib_params.x);
}
