// The shape's colour at a point, shared by the graphics path (render_mesh.frag) and
// the compute rasterizer (raster_resolve.comp), so both draw the same picture: the
// texture (premultiplied RGBA) or a flat fill, optionally under the distortion
// colour map and a red tint for an uncertified frame. Host side: compute/src/renderer.cpp.
#ifndef HSI_RENDER_SHADE_GLSL
#define HSI_RENDER_SHADE_GLSL

// Flags (push constants of both paths).
const uint kTextured = 1u;     // sample the texture (else the flat fill colour)
const uint kDistortion = 2u;   // blend the distortion colour map over it
const uint kUncertified = 4u;  // tint red (the frame could not be certified)

// Viridis (perceptually uniform), polynomial fit; hsi::vk::colormap() mirrors it on the host.
vec3 hsi_colormap(float t) {
  t = clamp(t, 0.0, 1.0);
  const vec3 c0 = vec3(0.2777273272234177, 0.005407344544966578, 0.3340998053353061);
  const vec3 c1 = vec3(0.1050930431085774, 1.404613529898575, 1.384590162594685);
  const vec3 c2 = vec3(-0.3308618287255563, 0.214847559468213, 0.09509516302823659);
  const vec3 c3 = vec3(-4.634230498983486, -5.799100973351585, -19.33244095627987);
  const vec3 c4 = vec3(6.228269936347081, 14.17993336680509, 56.69055260068105);
  const vec3 c5 = vec3(4.776384997670288, -13.74514537774601, -65.35303263337234);
  const vec3 c6 = vec3(-5.435455855934631, 4.645852612178535, 26.3124352495832);
  return clamp(c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6))))), 0.0, 1.0);
}


// The colour-map parameter of a vertex from its conformal distortion kappa = sigma1/sigma2,
// unclamped (interpolated, then clamped by hsi_colormap). A fold (sigma2 <= 0: kappa
// negative or infinite) or NaN saturates the map.
float hsi_kappa_t(float kappa, float dist_lo, float dist_inv) {
  return (kappa > 0.0 && kappa < 1e30) ? (kappa - dist_lo) * dist_inv : 1.0;
}

// Premultiplied colour: `base` is the texture sample (premultiplied) or the flat fill
// (straight, premultiplied here), kappa_t the interpolated colour-map parameter.
vec4 hsi_shade(vec4 base, float kappa_t, uint flags, float overlay_alpha) {
  vec4 c = (flags & kTextured) != 0u ? base : vec4(base.rgb * base.a, base.a);
  if ((flags & kDistortion) != 0u) c = mix(c, vec4(hsi_colormap(kappa_t), 1.0), overlay_alpha);
  if ((flags & kUncertified) != 0u) c.rgb = mix(c.rgb, vec3(0.92, 0.04, 0.04) * c.a, 0.55);
  return c;
}

#endif  // HSI_RENDER_SHADE_GLSL
