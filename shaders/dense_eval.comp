// Dense evaluation of a harmonic map (math.md §2) at a list of points or on a
// regular grid: one invocation per point, straight from the cage (O(cage) memory,
// no basis matrix). Compiled twice: HSI_REAL_DOUBLE = 1 (double, shaderFloat64)
// and 0 (float fallback). The host side is compute/src/dense_eval.cpp.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "hsi_complex.glsl"

layout(local_size_x = 64) in;

// Flag bits of out_flags (mirrored in dense_eval.h).
const uint kInside = 1u;     // the point is inside the shape (grid mode with a mask only)
const uint kDetPos = 2u;     // det J = |f_z|^2 - |f_zbar|^2 > 0
const uint kDetNeg = 4u;     // det J < 0
const uint kEvaluated = 8u;  // the fields were computed (not skipped as outside)

// push-constant flags
const uint kGridMode = 1u;
const uint kMask = 2u;
const uint kSkipOutside = 4u;

layout(push_constant) uniform Push {
  uint base;         // index of this pass's first point in the whole set (grid row-major)
  uint count;        // points in this pass
  uint flags;        // kGridMode | kMask | kSkipOutside
  uint width;        // grid width (grid mode)
  uint cage_loops;   // loops[0 .. cage_loops): (first vertex index, vertex count)
  uint shape_loops;  // then shape loops: (geom index of first vertex, vertex count), outer first
  uint hole_count;   // N
  uint cage_at;      // geom index of cage vertex 0
  uint holes_at;     // geom index of rho_0
  uint phi_at;       // geom index of phi_0 (m + N entries)
  uint psi_at;       // geom index of psi_0 (m + N entries)
  uint vertex_count; // m
} pc;

layout(std430, binding = 0) readonly buffer Loops { uvec2 loops[]; };
// geom[0] = grid origin, geom[1] = grid spacing, then the blocks named in pc.
layout(std430, binding = 1) readonly buffer Geom { Real2 geom[]; };
layout(std430, binding = 2) readonly buffer Points { Real2 points[]; };
layout(std430, binding = 3) writeonly buffer OutF { Real2 out_f[]; };
layout(std430, binding = 4) writeonly buffer OutFz { Real2 out_fz[]; };
layout(std430, binding = 5) writeonly buffer OutFzbar { Real2 out_fzbar_conj[]; };
layout(std430, binding = 6) writeonly buffer OutFields { Real4 out_fields[]; };  // sigma1, sigma2, sigma1/sigma2, E_SD
layout(std430, binding = 7) writeonly buffer OutFlags { uint out_flags[]; };

// Even-odd crossing test, the same arithmetic as hsi::point_in_loop (precise: no
// contraction into fma, so grid masks match the CPU bit for bit in double).
bool in_loop(uvec2 loop, Real2 p) {
  bool inside = false;
  const uint n = loop.y;
  for (uint i = 0u, j = n - 1u; i < n; j = i++) {
    const Real2 a = geom[loop.x + i], b = geom[loop.x + j];
    if ((a.y > p.y) != (b.y > p.y)) {
      precise Real x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (p.x < x) inside = !inside;
    }
  }
  return inside;
}

bool in_shape(Real2 p) {
  if (!in_loop(loops[pc.cage_loops], p)) return false;
  for (uint k = 1u; k < pc.shape_loops; ++k)
    if (in_loop(loops[pc.cage_loops + k], p)) return false;
  return true;
}

void main() {
  const uint local = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                     gl_LocalInvocationID.x;
  if (local >= pc.count) return;

  Real2 w;
  if ((pc.flags & kGridMode) != 0u) {
    const uint index = pc.base + local;
    const uint i = index % pc.width, j = index / pc.width;
    // origin + (i dx, j dy), evaluated exactly like the host's grid_point().
    precise Real x = geom[0].x + Real(i) * geom[1].x;
    precise Real y = geom[0].y + Real(j) * geom[1].y;
    w = Real2(x, y);
  } else {
    w = points[local];
  }

  uint flags = 0u;
  if ((pc.flags & kMask) != 0u && in_shape(w)) flags |= kInside;
  if ((pc.flags & kSkipOutside) != 0u && (flags & kInside) == 0u) {
    const Real nan = hsi_nan();
    out_f[local] = Real2(nan);
    out_fz[local] = Real2(nan);
    out_fzbar_conj[local] = Real2(nan);
    out_fields[local] = Real4(nan);
    out_flags[local] = flags;
    return;
  }

  // Cauchy coordinates, edge by edge (math.md §2). Edge z_j -> z_{j+1} has
  // A_{j+1} = z_{j+1} - z_j and L_j = log(B_{j+1}/B_j); with q = L_j / A_{j+1} it adds
  //   C_j += q B_{j+1},  C_{j+1} -= q B_j,  D_j -= q,  D_{j+1} += q   (times 1/(2 pi i)),
  // so Σ C φ gains q (B_{j+1} φ_j - B_j φ_{j+1}) and Σ D φ gains q (φ_{j+1} - φ_j).
  Real2 c_phi = Real2(0), c_psi = Real2(0), d_phi = Real2(0), d_psi = Real2(0);
  for (uint l = 0u; l < pc.cage_loops; ++l) {
    const uint first = loops[l].x, k = loops[l].y;
    Real2 z0 = geom[pc.cage_at + first];
    Real2 b0 = z0 - w;
    Real2 phi0 = geom[pc.phi_at + first], psi0 = geom[pc.psi_at + first];
    for (uint j = 0u; j < k; ++j) {
      const uint v = first + (j + 1u == k ? 0u : j + 1u);
      const Real2 z1 = geom[pc.cage_at + v];
      const Real2 b1 = z1 - w;
      const Real2 phi1 = geom[pc.phi_at + v], psi1 = geom[pc.psi_at + v];
      const Real2 q = cdiv(clog(cdiv(b1, b0)), z1 - z0);
      c_phi += cmul(q, cmul(b1, phi0) - cmul(b0, phi1));
      c_psi += cmul(q, cmul(b1, psi0) - cmul(b0, psi1));
      d_phi += cmul(q, phi1 - phi0);
      d_psi += cmul(q, psi1 - psi0);
      z0 = z1;
      b0 = b1;
      phi0 = phi1;
      psi0 = psi1;
    }
  }
  c_phi = div_2pi_i(c_phi);
  c_psi = div_2pi_i(c_psi);
  d_phi = div_2pi_i(d_phi);
  d_psi = div_2pi_i(d_psi);
  // One column per hole: C = log|w - rho| (real), D = 1/(w - rho).
  for (uint h = 0u; h < pc.hole_count; ++h) {
    const Real2 d = w - geom[pc.holes_at + h];
    const Real lg = Real(0.5) * hsi_ln(cabs2(d));
    const Real2 inv = cinv(d);
    const uint col = pc.vertex_count + h;
    const Real2 phi = geom[pc.phi_at + col], psi = geom[pc.psi_at + col];
    c_phi += lg * phi;
    c_psi += lg * psi;
    d_phi += cmul(phi, inv);
    d_psi += cmul(psi, inv);
  }

  // Paper Eq. 2-4: f = Σ C φ + conj(Σ C ψ), f_z = Σ D φ, conj(f_zbar) = Σ D ψ.
  const Real2 f = c_phi + cconj(c_psi);
  const Real a = cabs(d_phi), b = cabs(d_psi);  // |f_z|, |f_zbar|
  const Real sigma1 = a + b, sigma2 = a - b;
  const Real det = cabs2(d_phi) - cabs2(d_psi);
  const Real e_sd = Real(0.5) * (sigma1 * sigma1 + Real(1) / (sigma1 * sigma1) + sigma2 * sigma2 +
                                 Real(1) / (sigma2 * sigma2));
  flags |= kEvaluated;
  if (det > Real(0)) flags |= kDetPos;
  if (det < Real(0)) flags |= kDetNeg;

  out_f[local] = f;
  out_fz[local] = d_phi;
  out_fzbar_conj[local] = d_psi;
  out_fields[local] = Real4(sigma1, sigma2, sigma1 / sigma2, e_sd);
  out_flags[local] = flags;
}
