// The as-rigid-as-possible shape interpolation baseline (Alexa, Cohen-Or & Levin,
// "As-rigid-as-possible shape interpolation", SIGGRAPH 2000) on hsi's render mesh, and
// the per-triangle distortion measures the comparison uses (issue #11; the paper's
// Tables 3–4, Figs 3–5). A baseline, not the product: it lives in hsi_baselines.
//
// Method. For every triangle T and keyframe k, A_{k,T} = J_T(keyframe k) is the
// Jacobian of the piecewise-linear map rest → keyframe k, split by the polar
// decomposition A = R(θ)·S (R a rotation, S symmetric positive-definite; det A > 0 is
// required, so a keyframe with a flipped triangle is refused). Between keyframes k and
// k+1, with local parameter s = (t − t_k)/(t_{k+1} − t_k),
//     A_T(t) = R(α_{k,T} + s·δ_{k,T}) · ((1−s)·S_{k,T} + s·S_{k+1,T}).
// When keyframe k is the rest pose (S = I, α = 0) this is exactly Alexa et al.'s
// A(t) = R(s·α)·((1−s)I + s·S) for the map source → target; we decompose each keyframe
// against the rest mesh instead of taking the relative map keyframe k → k+1 because
// then (i) every keyframe has one decomposition shared by the segments on both sides
// of it, so the sequence is continuous and reproduces it exactly, (ii) the rule is
// symmetric in time, (iii) the target stretch is a convex combination of SPD matrices,
// so its κ never exceeds the two keyframes', and (iv) the energy below lives on the
// rest mesh, so one factorisation serves every segment.
//
// Rotation angles. θ is only known mod 2π. The increment δ_{k,T} ≡ θ_{k+1,T} − θ_{k,T}
// is lifted consistently over the mesh by quality-guided unwrapping: starting from the
// triangle nearest the area-weighted circular mean increment of its connected
// component, a Prim-style sweep over triangles sharing a vertex gives each triangle
// the representative nearest its already-lifted neighbour, smoothest pairs first.
// So a shape (or a limb) turning by about π between keyframes turns one way as a
// whole instead of tearing where the principal value jumps, a bend whose ends turn
// more than a full turn apart stays one piece, and turns accumulate across keyframes
// (0° → 175° → 350° turns 350°). The lift is then fixed up to 2π per component: its
// area-weighted mean turn is taken in [−π, π]. So what positions cannot tell (the
// whole shape turning +200° or −160° between two keyframes) is resolved the short
// way; add a keyframe in between to turn further.
//
// Positions. x(t) minimises E(x) = Σ_T area_T ‖J_T(x) − A_T(t)‖²_F: two Poisson
// problems (one per coordinate) with the cotangent stiffness matrix, factorised once
// (Eigen's SimplicialLDLT, one vertex per connected component pinned). E fixes x up to
// a translation per component; the translation is set so that the component's
// area-weighted centroid (lumped vertex masses) moves linearly between the keyframes'
// centroids — unlike pinning a vertex, that does not depend on the vertex numbering.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "hsi/baselines/mesh_keyframe.h"
#include "hsi/triangulate.h"

namespace hsi::baselines {

// Per-triangle distortion of a piecewise-linear map of a rest TriMesh.
struct MeshDistortion {
  std::vector<double> kappa;       // per triangle: σ1/σ2 (conformal distortion; +inf for a flipped or degenerate image)
  std::vector<double> isometric;   // per triangle: symmetric Dirichlet ½(σ1² + σ1⁻² + σ2² + σ2⁻²) (+inf as above)
  double max_kappa = 1, max_isometric = 2;  // over triangles
  int flipped = 0;                 // triangles with det J ≤ 0
};
// Throws InputError if positions has the wrong length or a non-finite entry, or the
// rest mesh has a degenerate triangle or an index out of range.
MeshDistortion mesh_distortion(const TriMesh& rest, std::span<const cd> positions);

using ArapKeyframe = MeshKeyframe;

struct ArapFrame {
  std::vector<cd> positions;
  // sqrt(E(x) / Σ_T area_T ‖A_T(t)‖²_F): how far the interpolated Jacobians are from
  // being the Jacobians of any mesh (0 at keyframes).
  double relative_residual = 0;
};

class ArapInterpolation {
 public:
  // ≥ 2 keyframes at strictly increasing times, each with rest.vertex_count() finite
  // positions and no flipped or degenerate triangle; the rest mesh with valid,
  // non-degenerate triangles covering every vertex. Otherwise InputError naming what
  // is wrong (which keyframe, which vertex or triangle).
  ArapInterpolation(const TriMesh& rest, std::vector<ArapKeyframe> keyframes);

  // Vertex positions at time t (clamped to the keyframes' range; InputError for NaN):
  // one sparse solve per call with the factorisation made in the constructor.
  std::vector<cd> positions(double t) const;
  // The same positions with the least-squares residual.
  ArapFrame frame(double t) const;
  // E(x) at time t for any positions (rest.vertex_count() of them).
  double energy(double t, std::span<const cd> positions) const;

  double t_begin() const;
  double t_end() const;
  int keyframe_count() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;  // immutable after construction: copies share it
};

}  // namespace hsi::baselines
