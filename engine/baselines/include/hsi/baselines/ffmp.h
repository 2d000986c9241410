// The FFMP baseline (free-form motion processing: Kircher & Garland, "Free-form motion
// processing", TOG 2008) on hsi's render mesh, as the paper's comparison describes it
// (issue #24; "FFMP needs to solve two large linear systems": one for the frames, one for
// the vertex positions). A baseline, not the product: it lives in hsi_baselines.
//
// Differential coordinates. Each triangle T carries a frame: in 2D, its Jacobian J_T
// from the rest mesh. (KG08's 3D frame is the triangle's edge pair and normal; its 2D
// analogue is the edge matrix X_T = J_T E_T. Its connection maps differ from the
// Jacobians' by the fixed rest matrices E, X_i⁻¹X_j = E_i⁻¹ (J_i⁻¹J_j) E_j, so blending
// either linearly is the same blend; only the least-squares weights below differ.) For
// every pair of triangles sharing an edge, the connection map Q_ij = J_i⁻¹ J_j says how
// j's frame sits in i's; it is rotation-invariant (J → R J leaves it unchanged), so a
// keyframe's pose does not enter it.
//
// Interpolation. Between keyframes k and k+1, s = (t − t_k)/(t_{k+1} − t_k), every
// connection map is blended linearly as a matrix: Q_ij(t) = (1−s) Q^k_ij + s Q^{k+1}_ij,
// as KG08 do. (A linear blend of matrices that turn shrinks them: that is the method's
// known scaling artefact, the paper's Figs 4 and 10, and it is kept.)
//
// Solve 1, the frames: J(t) minimises Σ_{i~j} w_ij (‖J_i Q_ij − J_j‖² + ‖J_j Q_ji − J_i‖²)/2
// over all triangles (both directions, so the result does not depend on which triangle
// of a pair comes first), w_ij the mean rest area of the pair, with one anchor triangle
// per edge-connected set of triangles held at its own interpolated frame: its polar
// decomposition J = R(θ) S with θ linear in s (each keyframe's θ lifted from the
// previous one the short way, |Δθ| ≤ π) and S blended linearly, as ARAP does for every
// triangle. The anchor is the triangle whose rest centroid is nearest the set's
// area-weighted rest centroid (FfmpOptions::anchor_triangle overrides it for its set).
// The system's two right-hand sides are the two rows of the frames. Its matrix depends on
// the blended connection maps, so it is factorised anew for every frame (Eigen's
// SimplicialLDLT; its pattern is built once per mesh).
//
// Solve 2, the positions: x minimises Σ_T area_T ‖J_T(x) − J_T(t)‖²_F, ARAP's Poisson
// system (cotangent stiffness), factorised once per mesh; each connected component's
// area-weighted centroid moves linearly between the keyframes' (as ARAP's).
//
// So keyframes are reproduced exactly (their connection maps and anchor are consistent),
// and a rigid or similarity motion stays one (every Q_ij is then the same rotation-free
// matrix, and the anchor carries the motion).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "hsi/baselines/mesh_keyframe.h"
#include "hsi/triangulate.h"

namespace hsi::baselines {

struct FfmpOptions {
  // The anchor of the edge-connected set of triangles that holds this triangle; −1: in
  // every set, the triangle nearest the set's area-weighted rest centroid.
  int anchor_triangle = -1;
};

struct FfmpFrame {
  std::vector<cd> positions;
  // sqrt of the frame system's least-squares residual over Σ w_ij ‖J_j‖² (both directions):
  // how far the blended connection maps are from those of any set of frames (0 at keyframes).
  double frame_residual = 0;
  // sqrt(E(x) / Σ_T area_T ‖J_T(t)‖²_F) of solve 2: how far the solved frames are from
  // the Jacobians of any mesh (0 at keyframes).
  double position_residual = 0;
  double frames_ms = 0;     // solve 1: assembling, factorising and solving the frame system
  double positions_ms = 0;  // solve 2: one solve with the factorisation made in the constructor
};

class FfmpInterpolation {
 public:
  // ≥ 2 keyframes at strictly increasing times, each with rest.vertex_count() finite
  // positions and no flipped or degenerate triangle (a connection map needs J⁻¹); the
  // rest mesh with valid, non-degenerate triangles covering every vertex. Otherwise
  // InputError naming what is wrong (which keyframe, which vertex or triangle).
  FfmpInterpolation(const TriMesh& rest, std::vector<MeshKeyframe> keyframes, FfmpOptions options = {});

  // Vertex positions at time t (clamped to the keyframes' range; InputError for NaN):
  // the two sparse solves of one frame.
  std::vector<cd> positions(double t) const;
  // The same positions with residuals and timings.
  FfmpFrame frame(double t) const;

  double t_begin() const;
  double t_end() const;
  int keyframe_count() const;
  // The anchor triangles, one per edge-connected set of triangles.
  std::vector<int> anchors() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;  // immutable after construction: copies share it
};

}  // namespace hsi::baselines
