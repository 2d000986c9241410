// hsib_playback.glsl run as a compute shader under Vulkan: the position of every
// vertex of `instances` copies of a bound mesh, written to a buffer. The test
// (tests/test_hsib_gpu.cpp) compares it with the C runtime; bench/bench_hsib_gpu
// times it against the CPU runtime. The same function a vertex shader calls.
#version 450
#extension GL_GOOGLE_include_directive : require
#define HSIB_MAX_ROWS 1024
#include "hsib_preamble_vulkan.glsl"
#include "hsib_playback.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 2) writeonly buffer Positions { vec2 positions[]; };
layout(push_constant) uniform Push {
  uint vertex_count;
  uint total;  // vertex_count * instances
} pc;

void main() {
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  if (i >= pc.total) return;
  positions[i] = hsib_position(int(i % pc.vertex_count));
}
