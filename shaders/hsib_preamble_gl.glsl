// OpenGL and WebGL2 preamble of hsib_playback.glsl (after "#version 330 core" or
// "#version 300 es"): rows in an RGBA32F texture (hsib_rows, no filtering: texelFetch),
// the frame's values as plain uniforms (hsib_pose, hsib_params, hsib_weights).
precision highp float;
precision highp int;
precision highp sampler2D;
uniform highp sampler2D hsib_rows;
#define HSIB_ROW_TEXEL(i) texelFetch(hsib_rows, ivec2((i) % textureSize(hsib_rows, 0).x, (i) / textureSize(hsib_rows, 0).x), 0)
#define HSIB_BEGIN_UNIFORMS
#define HSIB_UNIFORM uniform
#define HSIB_END_UNIFORMS
#define HSIB_VERTEX_INDEX gl_VertexID
