// The compute rasterizer's second pass (after raster.comp): one invocation per pixel
// reads its samples' triangles from the visibility buffer, shades each distinct
// triangle once at the pixel's centre (as the graphics path's MSAA shades once per
// pixel and primitive: attributes interpolated linearly, extrapolated where the
// centre lies outside the triangle; the texture's level of detail from the
// triangle's exact screen-space derivatives of the texture coordinates), blends
// each covered sample over the background (premultiplied "over"), averages the
// samples and writes the pixel. An uncertified frame's red border replaces the
// background inside the border.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "raster_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// Premultiplied colour of triangle t at pixel position c.
vec4 shade(uint t, vec2 c) {
  const uint i0 = tri[3u * t], i1 = tri[3u * t + 1u], i2 = tri[3u * t + 2u];
  const vec2 p0 = pixel_of(i0), d1 = pixel_of(i1) - p0, d2 = pixel_of(i2) - p0;
  const float area = cross2(d1, d2);
  // c = p0 + l1 d1 + l2 d2; a(c) = a0 + l1 (a1 - a0) + l2 (a2 - a0) for each attribute.
  const float inv = area != 0.0 ? 1.0 / area : 0.0;
  const float l1 = cross2(c - p0, d2) * inv, l2 = cross2(d1, c - p0) * inv;
  const vec2 dl1 = vec2(d2.y, -d2.x) * inv, dl2 = vec2(-d1.y, d1.x) * inv;  // (d/dx, d/dy) of l1, l2
  const vec2 u0 = uv[i0], du1 = uv[i1] - u0, du2 = uv[i2] - u0;
  const float k0 = hsi_kappa_t(float(fields[i0].z), pc.dist_lo, pc.dist_inv);
  const float dk1 = hsi_kappa_t(float(fields[i1].z), pc.dist_lo, pc.dist_inv) - k0;
  const float dk2 = hsi_kappa_t(float(fields[i2].z), pc.dist_lo, pc.dist_inv) - k0;
  vec4 base = pc.fill;
  if ((pc.flags & kTextured) != 0u)
    base = textureGrad(tex, u0 + l1 * du1 + l2 * du2, dl1.x * du1 + dl2.x * du2, dl1.y * du1 + dl2.y * du2);
  return hsi_shade(base, k0 + l1 * dk1 + l2 * dk2, pc.flags, pc.overlay_alpha);
}

void main() {
  const uvec2 px = gl_GlobalInvocationID.xy;
  if (px.x >= pc.width || px.y >= pc.height) return;
  const uint b = pc.border_px;
  const bool in_border = b > 0u && (px.x < b || px.y < b || px.x >= pc.width - b || px.y >= pc.height - b);
  const vec4 background = in_border ? pc.border_color : pc.background;
  const vec2 centre = vec2(px) + 0.5;
  const uint base = (px.y * pc.width + px.x) * pc.samples;
  vec4 sum = vec4(0.0);
  uint last = 0u;
  vec4 colour = vec4(0.0);
  for (uint k = 0u; k < pc.samples; ++k) {
    const uint id = vis[base + k];
    if (id == 0u) {
      sum += background;
      continue;
    }
    if (id != last) {  // a pixel's samples rarely see more than two triangles
      colour = shade(id - 1u, centre);
      last = id;
    }
    sum += colour + (1.0 - colour.a) * background;
  }
  imageStore(out_image, ivec2(px), sum / float(pc.samples));
}
