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
//
// Distortion, when the application defines HSIB_DERIVATIVES before the preamble:
//   derivative rows  per vertex 2T texels, texel 2(v*T + q) = d/dx of rows 4q..4q+3,
//             texel 2(v*T + q) + 1 = their d/dy (hsib_gpu_derivative_rows, from a
//             binding made with HSIB_BIND_DERIVATIVES), a second texture
//             (hsib_derivative_rows) or storage buffer; the same uniforms.
// hsib_jacobian(vertex) is mix(J0, J1, s) (the blend's Jacobian), and
// hsib_singular_values(vertex) its (sigma1, sigma2) as hsi defines them: sampled at
// the vertex, not the certificate's bound; sigma2 <= 0 where the map folds.
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

#ifdef HSIB_DERIVATIVES
// The blend's Jacobian at vertex `vertex`: columns df/dx and df/dy.
mat2 hsib_jacobian(int vertex) {
  int texels = int(hsib_params.z);
  vec4 ax = vec4(0.0);  // df/dx: (x, y in frame 0, x, y in frame 1)
  vec4 ay = vec4(0.0);  // df/dy
  for (int q = 0; q < texels; ++q) {
    vec4 dx = HSIB_DERIVATIVE_TEXEL(2 * (vertex * texels + q));
    vec4 dy = HSIB_DERIVATIVE_TEXEL(2 * (vertex * texels + q) + 1);
    int k = 4 * q;
    ax += dx.x * hsib_weights[k] + dx.y * hsib_weights[k + 1] + dx.z * hsib_weights[k + 2] + dx.w * hsib_weights[k + 3];
    ay += dy.x * hsib_weights[k] + dy.y * hsib_weights[k + 1] + dy.z * hsib_weights[k + 2] + dy.w * hsib_weights[k + 3];
  }
  return mat2(mix(ax.xy, ax.zw, hsib_params.x), mix(ay.xy, ay.zw, hsib_params.x));
}

// (sigma1, sigma2) = (|f_z| + |f_zbar|, |f_z| - |f_zbar|) of a Jacobian, with
// f_z = ((a + d) + i(c - b))/2 and f_zbar = ((a - d) + i(c + b))/2 for J = [a b; c d].
vec2 hsib_singular_values_of(mat2 J) {
  float fz = 0.5 * length(vec2(J[0].x + J[1].y, J[0].y - J[1].x));
  float fzbar = 0.5 * length(vec2(J[0].x - J[1].y, J[0].y + J[1].x));
  return vec2(fz + fzbar, fz - fzbar);
}

vec2 hsib_singular_values(int vertex) { return hsib_singular_values_of(hsib_jacobian(vertex)); }

// hsi's distortion measures of (sigma1, sigma2), meaningful where sigma2 > 0.
float hsib_conformal_distortion(vec2 sigma) { return sigma.x / sigma.y; }
float hsib_isometric_distortion(vec2 sigma) {
  vec2 s2 = sigma * sigma;
  return 0.5 * (s2.x + 1.0 / s2.x + s2.y + 1.0 / s2.y);
}
#endif
