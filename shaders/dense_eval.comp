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
const uint kRowPass = 8u;   // this dispatch: one invocation per grid row, its crossings -> rows
const uint kRowMask = 16u;  // the mask from the rows' crossings (grid mode, at most 32 loops)

// Crossings of a grid row with the mask shape's edges, at most kRowCap per row (a row
// with more falls back to the full test).
const uint kRowCap = 64u;
const uint kRowOverflow = 0xffffffffu;

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
  uint inva_at;      // geom index of 1/(z_{j+} - z_j), one per cage vertex (its edge to the next)
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
layout(std430, binding = 8) buffer RowCount { uint row_n[]; };    // per grid row: crossings or kRowOverflow
layout(std430, binding = 9) buffer RowCross { Real2 row_x[]; };   // row j: [j kRowCap, ...): (x, loop index)

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

// The y of grid row j, as main() computes it.
Real row_y(uint j) {
  precise Real y = geom[0].y + Real(j) * geom[1].y;
  return y;
}

// kRowPass: every crossing of row j with the shape's edges, in_loop's test and
// arithmetic (so the parities below are in_loop's, bit for bit).
void row_crossings(uint j) {
  const Real py = row_y(j);
  uint n = 0u;
  for (uint k = 0u; k < pc.shape_loops; ++k) {
    const uvec2 loop = loops[pc.cage_loops + k];
    for (uint i = 0u, jj = loop.y - 1u; i < loop.y; jj = i++) {
      const Real2 a = geom[loop.x + i], b = geom[loop.x + jj];
      if ((a.y > py) != (b.y > py)) {
        precise Real x = a.x + (py - a.y) * (b.x - a.x) / (b.y - a.y);
        if (n < kRowCap) row_x[j * kRowCap + n] = Real2(x, Real(k));
        ++n;
      }
    }
  }
  row_n[j] = n > kRowCap ? kRowOverflow : n;
}

// in_shape for grid point p of row j from the row's crossings: per loop, the parity
// of crossings right of p (in_loop's `p.x < x`); inside = odd for the outer loop and
// even for every hole.
bool in_shape_row(Real2 p, uint j) {
  const uint n = row_n[j];
  if (n == kRowOverflow) return in_shape(p);
  uint parity = 0u;
  for (uint c = 0u; c < n; ++c) {
    const Real2 e = row_x[j * kRowCap + c];
    if (p.x < e.x) parity ^= 1u << uint(e.y);
  }
  return parity == 1u;
}

void main() {
  const uint local = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                     gl_LocalInvocationID.x;
  if (local >= pc.count) return;
  if ((pc.flags & kRowPass) != 0u) {
    row_crossings(local);
    return;
  }

  Real2 w;
  uint row = 0u;
  if ((pc.flags & kGridMode) != 0u) {
    const uint index = pc.base + local;
    const uint i = index % pc.width;
    row = index / pc.width;
    // origin + (i dx, j dy), evaluated exactly like the host's grid_point().
    precise Real x = geom[0].x + Real(i) * geom[1].x;
    w = Real2(x, row_y(row));
  } else {
    w = points[local];
  }

  uint flags = 0u;
  if ((pc.flags & kMask) != 0u && ((pc.flags & kRowMask) != 0u ? in_shape_row(w, row) : in_shape(w))) flags |= kInside;
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
  // B_{j+}/B_j = B_{j+} conj(B_j) / |B_j|^2 with 1/|B_j|^2 carried from the edge
  // before, and 1/A from the host: one division per edge.
  Real2 c_phi = Real2(0), c_psi = Real2(0), d_phi = Real2(0), d_psi = Real2(0);
  for (uint l = 0u; l < pc.cage_loops; ++l) {
    const uint first = loops[l].x, k = loops[l].y;
    Real2 b0 = geom[pc.cage_at + first] - w;
    Real r0 = Real(1) / cabs2(b0);
    Real2 phi0 = geom[pc.phi_at + first], psi0 = geom[pc.psi_at + first];
    for (uint j = 0u; j < k; ++j) {
      const uint v = first + (j + 1u == k ? 0u : j + 1u);
      const Real2 b1 = geom[pc.cage_at + v] - w;
      const Real r1 = Real(1) / cabs2(b1);
      const Real2 phi1 = geom[pc.phi_at + v], psi1 = geom[pc.psi_at + v];
      const Real2 q = cmul(clog(cmul(b1, cconj(b0)) * r0), geom[pc.inva_at + first + j]);
      c_phi += cmul(q, cmul(b1, phi0) - cmul(b0, phi1));
      c_psi += cmul(q, cmul(b1, psi0) - cmul(b0, psi1));
      d_phi += cmul(q, phi1 - phi0);
      d_psi += cmul(q, psi1 - psi0);
      b0 = b1;
      r0 = r1;
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
