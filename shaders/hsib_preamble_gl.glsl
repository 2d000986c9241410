// OpenGL and WebGL2 preamble of hsib_playback.glsl (after "#version 330 core" or
// "#version 300 es"): rows in an RGBA32F texture (hsib_rows, no filtering: texelFetch),
// the frame's values as plain uniforms (hsib_pose, hsib_params, hsib_weights); with
// HSIB_DERIVATIVES defined, the derivative rows in a second such texture
// (hsib_derivative_rows).
precision highp float;
precision highp int;
precision highp sampler2D;
uniform highp sampler2D hsib_rows;
#define HSIB_ROW_TEXEL(i) texelFetch(hsib_rows, ivec2((i) % textureSize(hsib_rows, 0).x, (i) / textureSize(hsib_rows, 0).x), 0)
#ifdef HSIB_DERIVATIVES
uniform highp sampler2D hsib_derivative_rows;
#define HSIB_DERIVATIVE_TEXEL(i) texelFetch(hsib_derivative_rows, ivec2((i) % textureSize(hsib_derivative_rows, 0).x, (i) / textureSize(hsib_derivative_rows, 0).x), 0)
#endif
#define HSIB_BEGIN_UNIFORMS
#define HSIB_UNIFORM uniform
#define HSIB_END_UNIFORMS
#define HSIB_VERTEX_INDEX gl_VertexID
