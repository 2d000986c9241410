// Vulkan preamble of hsib_playback.glsl (after "#version 450" or later; SPIR-V):
// rows in a storage buffer, the frame's uniforms in a uniform buffer, both in
// descriptor set HSIB_SET at the bindings below (defaults 0, 0 and 1); with
// HSIB_DERIVATIVES defined, the derivative rows in a second storage buffer
// (HSIB_DERIVATIVES_BINDING, default 2).
#ifndef HSIB_SET
#define HSIB_SET 0
#endif
#ifndef HSIB_ROWS_BINDING
#define HSIB_ROWS_BINDING 0
#endif
#ifndef HSIB_FRAME_BINDING
#define HSIB_FRAME_BINDING 1
#endif
layout(std430, set = HSIB_SET, binding = HSIB_ROWS_BINDING) readonly buffer HsibRows { vec4 hsib_row_texels[]; };
#define HSIB_ROW_TEXEL(i) hsib_row_texels[(i)]
#ifdef HSIB_DERIVATIVES
#ifndef HSIB_DERIVATIVES_BINDING
#define HSIB_DERIVATIVES_BINDING 2
#endif
layout(std430, set = HSIB_SET, binding = HSIB_DERIVATIVES_BINDING) readonly buffer HsibDerivativeRows { vec4 hsib_derivative_texels[]; };
#define HSIB_DERIVATIVE_TEXEL(i) hsib_derivative_texels[(i)]
#endif
#define HSIB_BEGIN_UNIFORMS layout(std140, set = HSIB_SET, binding = HSIB_FRAME_BINDING) uniform HsibFrame {
#define HSIB_UNIFORM
#define HSIB_END_UNIFORMS };
#define HSIB_VERTEX_INDEX gl_VertexIndex
