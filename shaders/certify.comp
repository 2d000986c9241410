// Dense certification (math.md §6): the injectivity certificate of
// engine/src/certificate.cpp (the CPU reference) on the GPU, one invocation per
// boundary segment of the reference's breakpoint list (hsi::certificate_segments).
// Host side: compute/src/dense_certify.cpp. One pipeline, its pass chosen by pc.mode:
//   mode 2  once per shape, one invocation per (breakpoint i, column j): the basis
//           matrix at the breakpoints (the map-independent half of modes 0 and 1):
//           the column's terms of f_z and f_zz at point i, the weights of their
//           rounding-error bounds, and its weight in segment i's Lipschitz constant
//           -> basis[j S + i]
//   mode 3  per map, with that matrix: 8 breakpoints per workgroup, each a row
//           summed by 8 invocations over strided columns, then reduced in a fixed
//           order: f_z, conj f_zbar, f_zz, (conj f_zbar)' with their error bounds
//           -> vals[], and the Lipschitz constants of segment i -> lip[]
//   mode 0  instead of 2 + 3 where the matrix would not fit (the host decides): one
//           invocation per breakpoint, the same values straight from the cage -> vals[]
//   mode 1  one invocation per segment [p, q] (q = the next breakpoint of the loop):
//           the Lipschitz constants of f_zz and (conj f_zbar)' on the segment (from
//           lip[] after mode 3, else computed here), then the reference's test with
//           adaptive subdivision, depth first with an explicit stack (same pieces,
//           same order, same depth cap and piece budget; values at the midpoints
//           straight from the cage) -> out[]
//
// Double precision only (shaderFloat64): a float version could not keep the bounds
// sound at the margins the certificate works with. The piece test is the
// reference's, rounding allowances included: evaluated values carry an error bound
// from a running sum of term magnitudes, distances are lowered and Lipschitz
// constants raised by their rounding, and every bound formula gets an absolute
// allowance for its own few operations. The two evaluate f_z differently (the
// reference per cage vertex, this per cage edge) and so carry different error
// bounds; the verdicts differ only where the reference's margin is within ~1e-11 of
// zero relative to |f_z|. Assumes IEEE double +, -, *, /, sqrt (lavapipe, NVIDIA, AMD)
// and hsi_ln / hsi_atan2 good to a few ulps (hsi_complex.glsl).
#version 460
#extension GL_GOOGLE_include_directive : require

#if !HSI_REAL_DOUBLE
#error certify.comp needs HSI_REAL_DOUBLE=1 (the certificate is double precision only)
#endif
#include "hsi_complex.glsl"

layout(local_size_x = 64) in;

// Mirrored in dense_certify.cpp.
const uint kModeValues = 0u, kModeSegments = 1u, kModeBasis = 2u, kModeBasisValues = 3u;
const uint kStopAtFirstFailure = 1u;  // pc.flags
const uint kHaveLip = 2u;             // pc.flags: mode 1 reads lip[] (written by mode 3)
const uint kRows = 8u, kChunks = 8u;  // mode 3: rows per workgroup, invocations per row (kRows kChunks = 64)
// Segment status (out[].status).
const uint kCertified = 0u;  // every piece proved
const uint kFolds = 1u;      // |f_zbar| >= |f_z| at an end of the failing piece: a real fold
const uint kUndecided = 2u;  // depth cap or piece budget reached
const uint kSkipped = 3u;    // not started: another segment had failed (stop at first failure)
const uint kStopped = 4u;    // interrupted: another segment had failed (stop at first failure)
const uint kStack = 32u;     // explicit stack: max_depth <= kStack - 1 (the host checks)

const double kU = 1.1102230246251565e-16lf;  // unit roundoff 2^-53

layout(push_constant) uniform Push {
  uint mode;          // kModeValues or kModeSegments
  uint count;         // breakpoints (= segments)
  uint cage_loops;    // loops[0 .. cage_loops): (index of the loop's first cage vertex, vertex count)
  uint hole_count;    // N
  uint vertex_count;  // m
  uint cage_at;       // geom index of cage vertex 0 (m entries)
  uint holes_at;      // geom index of rho_0 (N entries)
  uint phi_at;        // geom index of phi_0 (m + N entries)
  uint psi_at;        // geom index of psi_0 (m + N entries)
  uint jumps_at;      // geom index of (|S_j^phi|, |S_j^psi|) upper bounds, m entries, then (|phi_log|, |psi_log|), N
  uint max_depth;     // CertificateOptions::max_depth
  uint max_pieces;    // CertificateOptions::max_pieces_per_segment (clamped to uint)
  uint flags;         // kStopAtFirstFailure | kHaveLip
  uint diff_at;       // mode 3: geom index of the column inputs (4 blocks of m + N, see basis_values)
  uint pad1, pad2;
} pc;

// f_z = a, conj f_zbar = b and their z-derivatives a1 = f_zz, b1 = (conj f_zbar)',
// with err = bounds on the absolute rounding error of (a, b, a1, b1).
struct Values {
  dvec2 a, b, a1, b1;
  dvec4 err;
};

struct SegmentOut {
  double arg;     // change of arg f_z over the proved pieces
  double margin;  // min over pieces of (lower |f_z| - upper |f_zbar|), failing piece included
  double sigma1, sigma2, k;
  double fail_x, fail_y;  // midpoint of the failing piece
  double abs_a, abs_b;    // |f_z|, |f_zbar| at the segment's first breakpoint
  uint status;
  uint pieces;
};

layout(std430, binding = 0) readonly buffer Loops { uvec2 loops[]; };
layout(std430, binding = 1) readonly buffer Geom { dvec2 geom[]; };
layout(std430, binding = 2) readonly buffer Points { dvec2 points[]; };
layout(std430, binding = 3) readonly buffer Next { uint next[]; };
layout(std430, binding = 4) buffer Vals { Values vals[]; };
layout(std430, binding = 5) writeonly buffer Out { SegmentOut out_seg[]; };
layout(std430, binding = 6) coherent buffer Control { uint stop; };
layout(std430, binding = 7) buffer Lip { dvec2 lip[]; };  // (L_a, L_b) per segment

// One column j of the basis matrix at breakpoint i (mode 2), for a cage column (vertex
// j, its edge to the next vertex j+) or a hole column (rho_h):
//   q   the term of f_z per unit input: (1/2 pi i) log(B_{j+}/B_j) / (z_{j+} - z_j)
//       (input phi_{j+} - phi_j), or 1/(w - rho) (input phi_{m+h})
//   e   the term of f_zz per unit phi_j: (1/2 pi i) (B_{j+} - B_{j-}) / (B_{j-} B_j B_{j+}),
//       or -1/(w - rho)^2
//   wq, we  upper bounds of |q|, |e| with the slack for their rounding, as mode 0 sums
//       them: (1 + |log|)/|A| / (2 pi) and (|B_{j+}| + |B_{j-}|)/|B_{j-} B_j B_{j+}| / (2 pi);
//       1/|w - rho| and 1/|w - rho|^2
//   wl  the column's weight in segment i's Lipschitz constants: 1/(2 pi dist^2) for a
//       cage vertex, 2/dist^3 for a hole point (lower distance bounds), or -1 where the
//       distance bound is not positive (the constant is then infinite)
struct BasisEntry {
  dvec2 q, e;
  double wq, we, wl, pad;
};
layout(std430, binding = 8) buffer Basis { BasisEntry basis[]; };

// Mode 3's partial sums, one slot per invocation.
shared dvec2 sh_a[64], sh_b[64], sh_a1[64], sh_b1[64], sh_lip[64];
shared dvec4 sh_err[64];
shared uint sh_bad[64];

double hsi_inf() { return packDouble2x32(uvec2(0u, 0x7ff00000u)); }

// The cage sums of math.md §2 at w, as the reference's values_at. D in edge form:
// edge z_e -> z_{e+1} with q = log(B_{e+1}/B_e) / A_{e+1} adds q (c_{e+1} - c_e) to
// Σ D c; E per vertex: E_j = (B_{j+1} - B_{j-1}) / (B_{j-1} B_j B_{j+1}); both times
// 1/(2 pi i). Error bounds: each term's rounding is a few ulps of a magnitude summed
// alongside ((1 + |log|)/|A| |Δc| for D: the log of a ratio carries an absolute
// error; (|B_{j+1}| + |B_{j-1}|)/|B_{j-1} B_j B_{j+1}| |c| for E), and a sum of n
// terms adds at most n ulps of the summed magnitudes: err = (2 n + 64) u Σ.
Values values_at(dvec2 w) {
  dvec2 a = dvec2(0), b = dvec2(0), a1 = dvec2(0), b1 = dvec2(0);
  double sa = 0.0lf, sb = 0.0lf, sa1 = 0.0lf, sb1 = 0.0lf;
  for (uint l = 0u; l < pc.cage_loops; ++l) {
    const uint first = loops[l].x, k = loops[l].y;
    dvec2 z0 = geom[pc.cage_at + first];
    dvec2 bm = geom[pc.cage_at + first + k - 1u] - w;
    dvec2 b0 = z0 - w;
    dvec2 phi0 = geom[pc.phi_at + first], psi0 = geom[pc.psi_at + first];
    for (uint j = 0u; j < k; ++j) {
      const uint v = first + (j + 1u == k ? 0u : j + 1u);
      const dvec2 z1 = geom[pc.cage_at + v];
      const dvec2 bp = z1 - w;
      const dvec2 phi1 = geom[pc.phi_at + v], psi1 = geom[pc.psi_at + v];
      // Edge j -> j+1 (D).
      const dvec2 L = clog(cdiv(bp, b0));
      const dvec2 A = z1 - z0;
      const dvec2 q = cdiv(L, A);
      const dvec2 dphi = phi1 - phi0, dpsi = psi1 - psi0;
      a += cmul(q, dphi);
      b += cmul(q, dpsi);
      const double wq = (1.0lf + cabs(L)) / cabs(A);
      sa += wq * cabs(dphi);
      sb += wq * cabs(dpsi);
      // Vertex j (E).
      const dvec2 e = cdiv(bp - bm, cmul(cmul(bm, b0), bp));
      a1 += cmul(e, phi0);
      b1 += cmul(e, psi0);
      const double we = (cabs(bp) + cabs(bm)) / (cabs(bm) * cabs(b0) * cabs(bp));
      sa1 += we * cabs(phi0);
      sb1 += we * cabs(psi0);
      z0 = z1;
      bm = b0;
      b0 = bp;
      phi0 = phi1;
      psi0 = psi1;
    }
  }
  Values v;
  v.a = div_2pi_i(a);
  v.b = div_2pi_i(b);
  v.a1 = div_2pi_i(a1);
  v.b1 = div_2pi_i(b1);
  sa *= kInv2Pi;
  sb *= kInv2Pi;
  sa1 *= kInv2Pi;
  sb1 *= kInv2Pi;
  // One column per hole: D = 1/(w - rho), E = -1/(w - rho)^2.
  for (uint h = 0u; h < pc.hole_count; ++h) {
    const dvec2 d = w - geom[pc.holes_at + h];
    const dvec2 inv = cinv(d);
    const dvec2 inv2 = cmul(inv, inv);
    const uint col = pc.vertex_count + h;
    const dvec2 phi = geom[pc.phi_at + col], psi = geom[pc.psi_at + col];
    v.a += cmul(phi, inv);
    v.b += cmul(psi, inv);
    v.a1 -= cmul(phi, inv2);
    v.b1 -= cmul(psi, inv2);
    const double r = 1.0lf / cabs(d);
    sa += cabs(phi) * r;
    sb += cabs(psi) * r;
    sa1 += cabs(phi) * r * r;
    sb1 += cabs(psi) * r * r;
  }
  const double c = (2.0lf * double(pc.vertex_count + pc.hole_count) + 64.0lf) * kU;
  v.err = c * dvec4(sa, sb, sa1, sb1);
  return v;
}

// hsi::segment_distance, lowered by a bound on its rounding error: never above the
// true distance from z to [p, q].
double distance_lower(dvec2 z, dvec2 p, dvec2 q) {
  const dvec2 ab = q - p;
  const double len2 = dot(ab, ab);
  double t = len2 > 0.0lf ? dot(z - p, ab) / len2 : 0.0lf;
  t = clamp(t, 0.0lf, 1.0lf);
  const double d = length(z - (p + t * ab));
  return d - 16.0lf * kU * (length(z) + length(p) + length(q));
}

// Mode 2: basis[t] for t = j S + i (t < S (m + N)).
void basis_entry(uint t) {
  const uint S = pc.count, i = t % S, j = t / S;
  const dvec2 w = points[i], p0 = w, q0 = points[next[i]];
  BasisEntry b;
  b.pad = 0.0lf;
  if (j < pc.vertex_count) {
    uint first = 0u, k = 1u;
    for (uint l = 0u; l < pc.cage_loops; ++l)
      if (j >= loops[l].x && j < loops[l].x + loops[l].y) {
        first = loops[l].x;
        k = loops[l].y;
      }
    const uint local = j - first;
    const uint vn = first + (local + 1u == k ? 0u : local + 1u), vp = first + (local == 0u ? k - 1u : local - 1u);
    const dvec2 z0 = geom[pc.cage_at + j], z1 = geom[pc.cage_at + vn];
    const dvec2 bm = geom[pc.cage_at + vp] - w, b0 = z0 - w, bp = z1 - w;
    // The same operations as values_at, edge j -> j+ and vertex j.
    const dvec2 L = clog(cdiv(bp, b0));
    const dvec2 A = z1 - z0;
    b.q = div_2pi_i(cdiv(L, A));
    b.wq = (1.0lf + cabs(L)) / cabs(A) * kInv2Pi;
    b.e = div_2pi_i(cdiv(bp - bm, cmul(cmul(bm, b0), bp)));
    b.we = (cabs(bp) + cabs(bm)) / (cabs(bm) * cabs(b0) * cabs(bp)) * kInv2Pi;
    const double d = distance_lower(z0, p0, q0);
    b.wl = d > 0.0lf ? kInv2Pi / (d * d) : -1.0lf;
  } else {
    const uint h = j - pc.vertex_count;
    const dvec2 rho = geom[pc.holes_at + h];
    const dvec2 d = w - rho;
    const dvec2 inv = cinv(d);
    b.q = inv;
    b.e = -cmul(inv, inv);
    const double r = 1.0lf / cabs(d);
    b.wq = r;
    b.we = r * r;
    const double dl = distance_lower(rho, p0, q0);
    b.wl = dl > 0.0lf ? 2.0lf / (dl * dl * dl) : -1.0lf;
  }
  basis[t] = b;
}

// Mode 3: row i of the matrix times the map's column inputs. geom[pc.diff_at ...]
// holds four blocks of m + N entries: x_j = phi_{j+} - phi_j (cage) or phi_{m+h}
// (holes); the same for psi; (|x_j^phi|, |x_j^psi|) and (|phi_j|, |psi_j|), both
// rounded up. The error bound is mode 0's with 8 more ulps per term for the two
// roundings the matrix adds (the 1/(2 pi i) folded into q and e, the product).
void basis_values(uint wg, uint lane) {
  const uint S = pc.count, M = pc.vertex_count + pc.hole_count;
  const uint r = lane % kRows, c = lane / kRows;
  const uint i = wg * kRows + r;
  dvec2 a = dvec2(0), b = dvec2(0), a1 = dvec2(0), b1 = dvec2(0), la = dvec2(0);
  dvec4 s = dvec4(0);
  uint bad = 0u;
  if (i < S) {
    for (uint j = c; j < M; j += kChunks) {
      const BasisEntry e = basis[j * S + i];
      const dvec2 xa = geom[pc.diff_at + j], xb = geom[pc.diff_at + M + j];
      const dvec2 ax = geom[pc.diff_at + 2u * M + j], av = geom[pc.diff_at + 3u * M + j];
      const dvec2 phi = geom[pc.phi_at + j], psi = geom[pc.psi_at + j];
      a += cmul(e.q, xa);
      b += cmul(e.q, xb);
      a1 += cmul(e.e, phi);
      b1 += cmul(e.e, psi);
      s += dvec4(e.wq * ax.x, e.wq * ax.y, e.we * av.x, e.we * av.y);
      if (e.wl < 0.0lf) bad = 1u;
      la += e.wl * geom[pc.jumps_at + j];
    }
  }
  sh_a[lane] = a;
  sh_b[lane] = b;
  sh_a1[lane] = a1;
  sh_b1[lane] = b1;
  sh_err[lane] = s;
  sh_lip[lane] = la;
  sh_bad[lane] = bad;
  barrier();
  if (c != 0u || i >= S) return;
  for (uint k = 1u; k < kChunks; ++k) {
    const uint o = k * kRows + r;
    a += sh_a[o];
    b += sh_b[o];
    a1 += sh_a1[o];
    b1 += sh_b1[o];
    s += sh_err[o];
    la += sh_lip[o];
    bad |= sh_bad[o];
  }
  Values v;
  v.a = a;
  v.b = b;
  v.a1 = a1;
  v.b1 = b1;
  v.err = (2.0lf * double(M) + 72.0lf) * kU * s;
  vals[i] = v;
  const double lip_up = 1.0lf + (2.0lf * double(M) + 40.0lf) * kU;
  lip[i] = bad != 0u ? dvec2(hsi_inf()) : la * lip_up;
}

void main() {
  const uint wg = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
  const uint index = wg * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
  if (pc.mode == kModeBasisValues) {
    basis_values(wg, gl_LocalInvocationID.x);
    return;
  }
  if (pc.mode == kModeBasis) {
    if (index < pc.count * (pc.vertex_count + pc.hole_count)) basis_entry(index);
    return;
  }
  if (index >= pc.count) return;

  if (pc.mode == kModeValues) {
    vals[index] = values_at(points[index]);
    return;
  }

  const bool stoppable = (pc.flags & kStopAtFirstFailure) != 0u;
  SegmentOut o;
  o.arg = 0.0lf;
  o.margin = hsi_inf();
  o.sigma1 = 0.0lf;
  o.sigma2 = hsi_inf();
  o.k = 0.0lf;
  o.fail_x = 0.0lf;
  o.fail_y = 0.0lf;
  o.status = kCertified;
  o.pieces = 0u;
  const uint jn = next[index];
  const Values vp0 = vals[index];
  o.abs_a = cabs(vp0.a);
  o.abs_b = cabs(vp0.b);
  if (stoppable && stop != 0u) {
    o.status = kSkipped;
    out_seg[index] = o;
    return;
  }

  // Lipschitz constants of f_zz and (conj f_zbar)' on the segment (math.md §6):
  // L = 1/(2 pi) Σ_j |S_j| / dist(z_j, σ)^2 + Σ_i 2 |c_log,i| / dist(rho_i, σ)^3, from
  // upper bounds of |S_j| (host) and lower bounds of the distances, raised by the
  // rounding of the sum.
  const dvec2 p0 = points[index], q0 = points[jn];
  double lip_a, lip_b;
  if ((pc.flags & kHaveLip) != 0u) {  // from the basis matrix (mode 3)
    lip_a = lip[index].x;
    lip_b = lip[index].y;
  } else {
    lip_a = 0.0lf;
    lip_b = 0.0lf;
    bool lip_ok = true;
    for (uint j = 0u; j < pc.vertex_count; ++j) {
      const double d = distance_lower(geom[pc.cage_at + j], p0, q0);
      lip_ok = lip_ok && d > 0.0lf;
      const double wgt = 1.0lf / (d * d);
      const dvec2 s = geom[pc.jumps_at + j];
      lip_a += wgt * s.x;
      lip_b += wgt * s.y;
    }
    lip_a *= kInv2Pi;
    lip_b *= kInv2Pi;
    for (uint h = 0u; h < pc.hole_count; ++h) {
      const double d = distance_lower(geom[pc.holes_at + h], p0, q0);
      lip_ok = lip_ok && d > 0.0lf;
      const double wgt = 2.0lf / (d * d * d);
      const dvec2 s = geom[pc.jumps_at + pc.vertex_count + h];
      lip_a += wgt * s.x;
      lip_b += wgt * s.y;
    }
    const double lip_up = 1.0lf + (2.0lf * double(pc.vertex_count + pc.hole_count) + 32.0lf) * kU;
    lip_a = lip_ok ? lip_a * lip_up : hsi_inf();
    lip_b = lip_ok ? lip_b * lip_up : hsi_inf();
  }

  // Depth-first over the pieces, exactly as the reference's recursion: the stack
  // holds pending right ends (point, values, depth); the current piece runs from
  // `left` to the top of the stack.
  dvec2 st_point[kStack];
  Values st_val[kStack];
  uint st_depth[kStack];
  uint sp = 0u;
  dvec2 left = p0;
  Values vl = vp0;
  st_point[0] = q0;
  st_val[0] = vals[jn];
  st_depth[0] = 0u;
  sp = 1u;
  while (sp > 0u) {
    --sp;
    const dvec2 q = st_point[sp];
    const Values vq = st_val[sp];
    const uint depth = st_depth[sp];
    const dvec2 p = left;
    const Values vp = vl;

    const double abs_ap = cabs(vp.a), abs_aq = cabs(vq.a), abs_bp = cabs(vp.b), abs_bq = cabs(vq.b);
    const double len = cabs(q - p) * (1.0lf + 4.0lf * kU);
    // Bounds of |f_zz| and |(conj f_zbar)'| on the piece (reference: fzz_max, bz_max).
    const double fzz_max = (((cabs(vp.a1) + vp.err.z) + (cabs(vq.a1) + vq.err.z)) * 0.5lf + lip_a * len * 0.5lf) *
                           (1.0lf + 8.0lf * kU);
    const double bz_max = (((cabs(vp.b1) + vp.err.w) + (cabs(vq.b1) + vq.err.w)) * 0.5lf + lip_b * len * 0.5lf) *
                          (1.0lf + 8.0lf * kU);
    const double a_avg_lo = ((abs_ap - vp.err.x) + (abs_aq - vq.err.x)) * 0.5lf;
    const double a_avg_hi = ((abs_ap + vp.err.x) + (abs_aq + vq.err.x)) * 0.5lf;
    const double b_avg_hi = ((abs_bp + vp.err.y) + (abs_bq + vq.err.y)) * 0.5lf;
    // The rounding of the few operations below and above, as an absolute allowance.
    const double tol = 8.0lf * kU * (a_avg_hi + b_avg_hi + fzz_max * len + bz_max * len);
    const double a_lo = a_avg_lo - fzz_max * len * 0.5lf - tol;
    const double a_hi = a_avg_hi + fzz_max * len * 0.5lf + tol;
    const double b_hi = b_avg_hi + bz_max * len * 0.5lf + tol;
    // f_z maps the piece into the disc |w - f_z(p)| <= fzz_max len, which must exclude 0.
    const bool arg_ok = fzz_max * len + vp.err.x + tol < abs_ap;
    const bool folds_here = abs_bp >= abs_ap || abs_bq >= abs_aq;
    if (a_lo > b_hi && arg_ok) {
      o.pieces++;
      const dvec2 ratio = cdiv(vq.a, vp.a);
      o.arg += hsi_atan2(ratio.y, ratio.x);
      o.margin = min(o.margin, a_lo - b_hi);
      o.sigma1 = max(o.sigma1, a_hi + b_hi);
      o.sigma2 = min(o.sigma2, a_lo - b_hi);
      o.k = max(o.k, b_hi / a_lo * (1.0lf + 2.0lf * kU));
      left = q;
      vl = vq;
      continue;
    }
    const bool stopped = stoppable && stop != 0u;
    if (folds_here || depth >= pc.max_depth || o.pieces >= pc.max_pieces || stopped) {
      o.status = folds_here                                        ? kFolds
                 : depth >= pc.max_depth || o.pieces >= pc.max_pieces ? kUndecided
                                                                      : kStopped;
      o.pieces++;
      o.margin = min(o.margin, a_lo - b_hi);
      precise const dvec2 mid = (p + q) * 0.5lf;
      o.fail_x = mid.x;
      o.fail_y = mid.y;
      break;
    }
    precise const dvec2 mid = (p + q) * 0.5lf;
    st_point[sp] = q;
    st_val[sp] = vq;
    st_depth[sp] = depth + 1u;
    st_point[sp + 1u] = mid;
    st_val[sp + 1u] = values_at(mid);
    st_depth[sp + 1u] = depth + 1u;
    sp += 2u;
  }
  if (o.status != kCertified && stoppable) atomicOr(stop, 1u);
  out_seg[index] = o;
}
