// The GE baseline (geodesic-elastic interpolation, as the paper's comparison runs it:
// [SGK19] Smith, de Goes & Kim, "Analytic Eigensystems for Isotropic Distortion
// Energies", TOG 2019) on hsi's render mesh (issue #24; the paper's Tables 3–4, Figs
// 3–5). A baseline, not the product: it lives in hsi_baselines.
//
// Target. Per triangle T and keyframe k, M_{k,T} = J_{k,T}ᵀ J_{k,T} is the pull-back
// metric of the keyframe (J its Jacobian from the rest mesh). Between keyframes k and
// k+1, with s = (t − t_k)/(t_{k+1} − t_k), the target metric is the linear blend
// M_T(t) = (1−s) M_{k,T} + s M_{k+1,T} — the paper's Sec. 4.1 blend, ours too, here per
// triangle of the whole mesh instead of at boundary samples.
//
// Energy. A frame x minimises E(x) = Σ_T area_T Ψ(F_T(x)) with F_T = J_T(x) G_T⁻¹,
// G_T = L_Tᵀ where M_T = L_T L_Tᵀ (Cholesky): Ψ(F) = ½(‖F‖²_F + ‖F⁻¹‖²_F) is the
// symmetric Dirichlet energy, and Ψ(F_T) = ½(Tr(M_T⁻¹ J_TᵀJ_T) + Tr(M_T (J_TᵀJ_T)⁻¹)),
// the paper's Eq. 7 with M_g = M_T. Its minimum, 2 per unit area, is reached where J_T
// realises M_T up to a rotation; it is +∞ where a triangle degenerates (a barrier).
//
// Solver. Newton on all vertex coordinates, warm-started from the previous frame (the
// first frame of a sequence from the keyframe nearest in time). The Hessian is
// Σ_T area_T B_Tᵀ H⁺(F_T) B_T, with vec F_T = B_T x_T and H⁺ the per-triangle 4×4
// Hessian of Ψ with every eigenvalue of SGK19's analytic eigensystem clamped at 0 (only
// the twist's, 1 − (σ1² − σ1σ2 + σ2²)/(σ1³σ2³), can be negative): PSD by construction,
// no numerical eigendecomposition. Each iteration factorises it with Eigen's
// SimplicialLDLT (the pattern built once per mesh, its
// ordering analysed once per frame; a ridge of 1e-12·max diag, ×10 per
// retry, only if the factorisation fails). Line search: the first trial step is
// min(1, safe_fraction·s_max), s_max the largest step that degenerates no triangle (the
// smallest positive root over triangles of det J_T(x + s·d) = 0), so no triangle ever
// flips; then backtracking until Armijo's condition holds. Converged when an accepted
// step lowers E by less than tolerance·E, or the Newton decrement −gᵀd/2 is below it
// (the same relative test as ours, NewtonOptions::tolerance).
//
// Rigid motion. E is blind to translation and rotation. During Newton, per connected
// component, one vertex is pinned and a second one (the farthest from it along x at the
// warm start) keeps its y, which removes exactly those three directions. After the solve
// each component is moved rigidly so that (i) its area-weighted centroid (lumped vertex
// masses) moves linearly between the keyframes' centroids, as ARAP's does, and (ii) its
// mean turn, arg Σ_T area_T f_z,T (f_z the conformal part of J_T), moves linearly between
// the keyframes', each keyframe's lifted from the previous one the short way (|Δ| ≤ π).
// So keyframes are reproduced (to the solve's tolerance) and a rigid motion stays rigid.
// A component whose mean f_z vanishes (parts turning against each other so that their
// conformal parts cancel) has no defined turn; the solve's own rotation is kept there.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "hsi/baselines/mesh_keyframe.h"
#include "hsi/triangulate.h"

namespace hsi::baselines {

struct GeOptions {
  double tolerance = 5e-8;     // relative decrease of E that counts as converged (ours: NewtonOptions::tolerance)
  int max_iterations = 1000;   // Newton steps per frame; a frame that needs more is reported not converged
  double armijo = 1e-4;        // sufficient-decrease factor
  double shrink = 0.5;         // backtracking factor
  double safe_fraction = 0.8;  // first trial step: min(1, safe_fraction · s_max) (ours: the same)
  int max_backtracks = 60;
};

struct GeFrame {
  double time = 0;
  std::vector<cd> positions;   // no triangle flipped (det J > 0 everywhere) when the start had none
  double energy = 0;           // E(x) / Σ_T area_T: ≥ 2, = 2 iff every triangle realises its target metric
  int iterations = 0;          // Newton steps taken
  int factorisations = 0;      // sparse Cholesky factorisations (one per iteration, more when a ridge was needed)
  bool converged = false;      // false: max_iterations reached, or no descent left before the tolerance
  double ms = 0;               // wall time of this frame's solve (Newton and the rigid placement)
};

// The symmetric Dirichlet energy Ψ(F) = ½(‖F‖² + ‖F⁻¹‖²) of a 2×2 F with det F > 0, its
// gradient and SGK19's analytic eigensystem of its 4×4 Hessian, all in vec(F) order
// (column-major: F00, F10, F01, F11). With F = U Σ Vᵀ (U, V rotations, σ1 ≥ σ2 > 0):
// scalings U diag(1,0) Vᵀ and U diag(0,1) Vᵀ (eigenvalues 1 + 3σ_i⁻⁴), the flip
// U [[0,1],[1,0]] Vᵀ/√2 (1 + (σ1² + σ1σ2 + σ2²)/(σ1³σ2³)) and the twist
// U [[0,−1],[1,0]] Vᵀ/√2 (1 − (σ1² − σ1σ2 + σ2²)/(σ1³σ2³)).
struct SymmetricDirichletEigensystem {
  double psi = 0;
  Eigen::Vector4d gradient;      // ∂Ψ/∂vec(F)
  Eigen::Vector4d eigenvalues;   // scaling 1, scaling 2, flip, twist
  Eigen::Matrix4d eigenvectors;  // columns, orthonormal, in the order of eigenvalues
  // Σ_i λ_i q_i q_iᵀ; with project, every λ_i clamped at 0 first (the PSD projection).
  Eigen::Matrix4d hessian(bool project) const;
};
// InputError if F is not finite or det F ≤ 0.
SymmetricDirichletEigensystem symmetric_dirichlet_eigensystem(const Eigen::Matrix2d& F);

class GeInterpolation {
 public:
  // ≥ 2 keyframes at strictly increasing times, each with rest.vertex_count() finite
  // positions and no flipped or degenerate triangle; the rest mesh with valid,
  // non-degenerate triangles covering every vertex. Otherwise InputError naming what
  // is wrong (which keyframe, which vertex or triangle).
  GeInterpolation(const TriMesh& rest, std::vector<MeshKeyframe> keyframes, GeOptions options = {});

  // Frames at the given times (any order, usually increasing), each solve warm-started
  // from the previous frame; the first from the keyframe nearest times[0]. progress, if
  // given, is called after each frame with it, its index and the number of frames.
  std::vector<GeFrame> sequence(std::span<const double> times,
                                const std::function<void(const GeFrame&, int, int)>& progress = {}) const;
  // One frame at time t (clamped to the keyframes' range), Newton from `start`
  // (rest.vertex_count() finite positions with no flipped or degenerate triangle:
  // InputError otherwise).
  GeFrame frame(double t, std::span<const cd> start) const;

  // E(x) at time t (+∞ if a triangle of x is flipped or degenerate), its gradient
  // (2 per vertex: x then y) and its Hessian, exact or with the per-triangle PSD
  // projection the solver uses. For tests; x must have no flipped triangle for the
  // derivatives (InputError otherwise).
  double energy(double t, std::span<const cd> x) const;
  Eigen::VectorXd gradient(double t, std::span<const cd> x) const;
  Eigen::SparseMatrix<double> hessian(double t, std::span<const cd> x, bool project) const;

  double t_begin() const;
  double t_end() const;
  int keyframe_count() const;
  const GeOptions& options() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;  // immutable after construction: copies share it
};

}  // namespace hsi::baselines
