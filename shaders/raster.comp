// The compute rasterizer's first pass (renderer.h, Rasterizer::kCompute): every
// triangle of the deformed mesh writes 1 + its index into the visibility-buffer
// samples it covers with atomicMax, so each sample ends up holding the last triangle
// in drawing order that covers it, the one the graphics path leaves on top.
// raster_resolve.comp then shades once per pixel and triangle. Unlike the graphics
// path, this runs on every SM of a compute GPU (the H100 draws on 2 of its 66 TPCs).
//
// pass 0: kLanes invocations per triangle, striding over its bounding box's pixels
//         (the atomics' latency is hidden by more of them in flight); a triangle
//         whose bounding box spans more than kLargePixels pixels is queued for
//         pass 1 instead.
// pass 1: a fixed number of workgroups (they return at once when nothing was
//         queued) take the queued triangles in turn, each workgroup's invocations
//         striding over a triangle's bounding box.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "raster_common.glsl"

layout(local_size_x = 64) in;

const uint kLargePixels = 256u;
const uint kLanes = 4u;  // renderer.cpp's kRasterLanes

// cross(b - a, s - a), with the edge's endpoints taken in a canonical order
// (lexicographic by position) so that two triangles sharing an edge compute
// bit-identical values (of opposite sign): a sample exactly on the edge is covered
// by both, any other by exactly one, whatever the rounding; no cracks between
// triangles. `precise` forbids fusing or reordering that could break the symmetry.
float edge_function(vec2 a, vec2 b, vec2 s) {
  const bool swap = a.x > b.x || (a.x == b.x && a.y > b.y);
  const vec2 lo = swap ? b : a, hi = swap ? a : b;
  precise const float e = (hi.x - lo.x) * (s.y - lo.y) - (hi.y - lo.y) * (s.x - lo.x);
  return swap ? -e : e;
}

struct Triangle {
  vec2 p0, p1, p2;
  float orientation;  // > 0 counter-clockwise in pixel coordinates, < 0 clockwise
  uvec2 lo, hi;       // pixels whose samples it may cover (inclusive), inside the image
  bool empty;
};

Triangle load(uint t) {
  Triangle T;
  T.p0 = pixel_of(tri[3u * t]);
  T.p1 = pixel_of(tri[3u * t + 1u]);
  T.p2 = pixel_of(tri[3u * t + 2u]);
  T.orientation = edge_function(T.p0, T.p1, T.p2);
  const vec2 lo = min(min(T.p0, T.p1), T.p2), hi = max(max(T.p0, T.p1), T.p2);
  // A degenerate triangle covers nothing; a non-finite position (which the graphics
  // path would also leave undrawn) must not reach the integer conversions.
  T.empty = T.orientation == 0.0 || any(isnan(lo)) || any(isnan(hi)) || any(isinf(lo)) || any(isinf(hi));
  if (T.empty) return T;
  // Sample x + s (0 < s < 1) can lie in [lo.x, hi.x] only for floor(lo.x) - 1 <= x <= floor(hi.x).
  const vec2 a = max(floor(lo) - 1.0, vec2(0.0));
  const vec2 b = min(floor(hi), vec2(float(pc.width) - 1.0, float(pc.height) - 1.0));
  T.empty = a.x > b.x || a.y > b.y;
  if (T.empty) return T;
  T.lo = uvec2(a);
  T.hi = uvec2(b);
  return T;
}

void cover_pixel(const Triangle T, uint x, uint y, uint id) {
  const uint base = (y * pc.width + x) * pc.samples;
  for (uint k = 0u; k < pc.samples; ++k) {
    const vec2 s = vec2(float(x), float(y)) + sample_location(pc.samples, k);
    const float e0 = edge_function(T.p0, T.p1, s), e1 = edge_function(T.p1, T.p2, s), e2 = edge_function(T.p2, T.p0, s);
    const bool inside = T.orientation > 0.0 ? (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) : (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
    // The result unused: a reduction the invocation does not wait for.
    if (inside) atomicMax(vis[base + k], id);
  }
}

void main() {
  if (pc.pass == 0u) {
    const uint invocation =
        (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    const uint t = invocation / kLanes, lane = invocation % kLanes;
    if (t >= pc.triangles) return;
    const Triangle T = load(t);
    if (T.empty) return;
    const uvec2 extent = T.hi - T.lo + 1u;
    const uint n = extent.x * extent.y;
    if (n > kLargePixels) {
      if (lane == 0u) large[atomicAdd(large_count, 1u)] = t;
      return;
    }
    for (uint i = lane; i < n; i += kLanes) cover_pixel(T, T.lo.x + i % extent.x, T.lo.y + i / extent.x, t + 1u);
    return;
  }
  for (uint q = gl_WorkGroupID.x; q < large_count; q += gl_NumWorkGroups.x) {
    const uint t = large[q];
    const Triangle T = load(t);
    const uvec2 extent = T.hi - T.lo + 1u;
    const uint n = extent.x * extent.y;
    for (uint i = gl_LocalInvocationID.x; i < n; i += gl_WorkGroupSize.x)
      cover_pixel(T, T.lo.x + i % extent.x, T.lo.y + i / extent.x, t + 1u);
  }
}
