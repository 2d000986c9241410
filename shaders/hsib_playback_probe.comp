// hsib_playback.glsl run as a compute shader under Vulkan: the position of every
// vertex of `instances` copies of a bound mesh, written to a buffer, and, built with
// HSIB_DERIVATIVES, its singular values (sigma1, sigma2) too. The tests
// (tests/test_hsib_gpu.cpp) compare them with the C runtime; bench/bench_hsib_gpu
// times it against the CPU runtime. The same functions a vertex shader calls.
#version 450
#extension GL_GOOGLE_include_directive : require
#define HSIB_MAX_ROWS 1024
#define HSIB_DERIVATIVES_BINDING 3
#include "hsib_preamble_vulkan.glsl"
#include "hsib_playback.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 2) writeonly buffer Positions { vec2 positions[]; };
#ifdef HSIB_DERIVATIVES
layout(std430, set = 0, binding = 4) writeonly buffer Sigmas { vec2 sigmas[]; };
#endif
layout(push_constant) uniform Push {
  uint vertex_count;
  uint total;  // vertex_count * instances
} pc;

void main() {
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  if (i >= pc.total) return;
  int vertex = int(i % pc.vertex_count);
  positions[i] = hsib_position(vertex);
#ifdef HSIB_DERIVATIVES
  sigmas[i] = hsib_singular_values(vertex);
#endif
}
