// Throughput probe (compute/src/diagnostics.cpp): eight independent chains of
// fused multiply-adds per invocation, in the precision of HSI_REAL_DOUBLE, so a large
// dispatch measures how much arithmetic the queue's compute work actually reaches.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "hsi_complex.glsl"

layout(local_size_x = 256) in;

layout(push_constant) uniform Push {
  uint iterations;
} pc;

layout(std430, binding = 0) writeonly buffer Out { Real out_v[]; };

void main() {
  const uint id = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
  const Real m = Real(0.999999), c = Real(1e-7);
  Real a0 = Real(id & 1023u) * Real(1e-6), a1 = a0 + Real(1), a2 = a0 + Real(2), a3 = a0 + Real(3);
  Real a4 = a0 + Real(4), a5 = a0 + Real(5), a6 = a0 + Real(6), a7 = a0 + Real(7);
  for (uint i = 0u; i < pc.iterations; ++i) {
    a0 = fma(a0, m, c);
    a1 = fma(a1, m, c);
    a2 = fma(a2, m, c);
    a3 = fma(a3, m, c);
    a4 = fma(a4, m, c);
    a5 = fma(a5, m, c);
    a6 = fma(a6, m, c);
    a7 = fma(a7, m, c);
  }
  out_v[id] = ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7));
}
