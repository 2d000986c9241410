// The CCW16 baseline (Chien, Chen & Weber 2016, "Bounded distortion harmonic shape
// interpolation", as our paper describes it in §1–2, Fig. 2 and Fig. 8): blend the
// keyframes' holomorphic derivatives pointwise, then integrate them. Not part of the
// product (issue #11): it is here to compare against, and to show that it breaks on
// shapes with holes.
//
// Keyframe k is f_k = Φ_k + conj(Ψ_k) + Σ_i ω_i log|w − ρ_i| (paper Eq. 1). From its
// coefficients (paper Eq. 4), with the log columns included, come two holomorphic
// functions that are single-valued in Ω (their primitives are not, on a shape with holes):
//     a_k = f_z = Σ_j D_j φ_j,     b_k = conj(f_zbar) = Σ_j D_j ψ_j,
// and the second dilatation ν_k = b_k / a_k (= Ψ_k'/Φ_k' away from the log terms),
// holomorphic, |ν_k| < 1 for a locally injective keyframe.
//
// Between keyframes k and k+1, with s = (t − t_k) / (t_{k+1} − t_k) (CCW16's η–ν blend):
//     log a(t) = (1 − s) log a_k + s log a_{k+1},  i.e.  a(t) = a_k exp(s λ_k),  λ_k = log(a_{k+1}/a_k)
//     ν(t)     = (1 − s) ν_k + s ν_{k+1},                b(t) = ν(t) a(t)
// Sums, products and exponentials of holomorphic functions are holomorphic, so the blend
// is evaluated pointwise and exactly wherever it is needed: no fit. (Blending on ∂Ω and
// extending inside by the Cauchy integral, as a boundary discretisation does, gives these
// same functions up to its discretisation error.) Pointwise |ν(t)| ≤ (1 − s)|ν_k| + s|ν_{k+1}|,
// so the conformal distortion κ = (1 + |ν|)/(1 − |ν|) stays within the keyframes' (CCW16's
// guarantee; the isometric distortion is not bounded by it).
//
// The frame is the integral (positions up to the translation convention below)
//     f(t)(w) = f(t)(w_0) + ∫_{w_0}^{w} a(t) dz + conj(b(t) dz),
//     f(t)(w_0) = (1 − s) f_k(w_0) + s f_{k+1}(w_0),   w_0 = the anchor = the shape's outer vertex 0,
// along straight pieces (at most max_piece × the shape's diagonal long) with Gauss–Legendre
// quadrature. At keyframe times the frame is the keyframe (the anchor's image is the keyframe's).
//
// Branch of λ_k: continued along every path in steps that turn arg by far less than π. It is
// single-valued in Ω when a_k and a_{k+1} wind equally around every hole (checked: keyframes
// in one homotopy class). Its constant 2πi m is chosen so that the mean relative rotation
// Im λ_k over the outer boundary samples lies in (−π, π] (the smaller turn between keyframes).
//
// Why it fails with holes (paper Fig. 2): f(t) is single-valued only if every period
//     P_i(t) = ∮_{counter-clockwise around hole i} a(t) dz + conj(b(t) dz)
// vanishes. For a keyframe P_i = 2πi (φ_log,i − conj ψ_log,i) = 0; for the blend it is not, in
// general, and the frame integrated along a spanning tree of a mesh tears along a seam by P_i.
// Even keyframes related by a rotation e^{iθ} give P ≠ 0: ν turns by e^{−2iθ}, and its linear
// blend is no rotation; with f_{k+1} = r f_k + c the period is exactly
//     P_i(s) = (r^s − conj(r^s ((1 − s) + s conj(r)/r))) · 2πi φ_log,i     (0 when r > 0).
#pragma once

#include <array>
#include <span>
#include <utility>
#include <vector>

#include "hsi/harmonic_map.h"
#include "hsi/triangulate.h"

namespace hsi::baselines {

struct Ccw16Keyframe {
  double time = 0;
  HarmonicMap map;  // over the scene's cage (hsi/harmonic_map.h)
};

struct Ccw16Options {
  int samples = 10000;     // boundary samples where keyframes are checked and λ's branch is chosen
  int quadrature = 10;     // Gauss–Legendre nodes per piece
  double max_piece = 0.025;  // longest straight piece integrated at once, relative to the shape's diagonal
};

struct Ccw16Frame {
  double t = 0;
  std::vector<cd> positions;        // f at the requested points (rest positions), integrated from the anchor
  std::vector<cd> fz, fzbar;        // f_z = a(t), f_zbar = conj(b(t)) at those points
  std::vector<double> hole_period;  // per hole: |P_i| (0 = integrable); empty when simply connected
  double max_kappa = 1, max_isometric = 2;  // over the points: κ = (|f_z|+|f_zbar|)/(|f_z|−|f_zbar|), ½(σ1²+σ1⁻²+σ2²+σ2⁻²)
  double max_nu = 0;                // over the points: |ν(t)| = |f_zbar| / |f_z|

  // On a mesh (frame(t, mesh) only):
  std::vector<cd> periods;          // per hole: P_i, counter-clockwise around the hole
  // Per hole: the largest |f(u) + ∫_u^v df − f(v)| over mesh edges (u, v) outside the spanning
  // tree whose tree loop winds once around this hole and no other: two paths around the hole
  // disagree by this much, the tear along the seam (= |P_i| up to quadrature).
  std::vector<double> seam_jump;
  // The largest |f(u) + ∫_u^v df − f(v) − Σ_i n_i P_i| over all mesh edges outside the tree
  // (n_i: how often the edge's tree loop winds around hole i): 0 up to quadrature error.
  double closure_error = 0;
};

// What frame() needs of a mesh and not of t: a spanning tree from the vertex nearest the
// anchor (grown first without crossing the cut rays from each hole point ρ_i away from that
// vertex, so the seam of a tear lies along the cut), Gauss nodes on every edge, the keyframes'
// derivatives there and λ_k's branch continued along the tree. Make it once per mesh.
class Ccw16Mesh {
 public:
  int vertex_count() const { return static_cast<int>(vertices_.size()); }
  int base_vertex() const { return base_; }
  // Parent of each vertex in the spanning tree (−1 at the base vertex).
  const std::vector<int>& parent() const { return parent_; }
  // Mesh edges (u, v) not in the tree (each once, u < v).
  std::vector<std::array<int, 2>> non_tree_edges() const;

 private:
  friend class Ccw16Interpolation;
  struct Edge {
    int from = 0, to = 0;  // integration direction (parent → child on the tree)
    bool tree = false;
    int node_begin = 0, node_end = 0;  // Gauss nodes, in order from → to
  };
  std::vector<cd> vertices_;
  int base_ = -1;
  std::vector<int> parent_, parent_edge_, order_;  // order_: vertices in BFS order (base first)
  std::vector<Edge> edges_;
  std::vector<int> winding_;          // non-tree edges × holes: n_i of the edge's tree loop (row-major)
  std::vector<std::vector<std::pair<int, int>>> hole_edges_;  // per hole: (edge, ±1) counter-clockwise around it
  int anchor_begin_ = 0, anchor_end_ = 0;  // nodes of the piece anchor → base vertex
  std::vector<cd> node_dz_;           // per node: Gauss weight × dz, so ∫ g dz ≈ Σ g(node) node_dz
  // Values at every point: vertices first, then the nodes (node index i is point V + i).
  Eigen::MatrixXcd a_, b_;            // points × keyframes
  Eigen::MatrixXcd lambda_;           // points × (keyframes − 1): λ_k, branch continued
};

class Ccw16Interpolation {
 public:
  // ≥ 2 keyframes, increasing finite times, maps of the cage's size with ψ_log = conj φ_log,
  // each locally injective at the boundary samples (f_z ≠ 0, |ν| < 1, and f_z without zeros in
  // Ω by the argument principle), consecutive keyframes with f_z winding equally around every
  // hole; else InputError naming the keyframe and the problem. Shapes with holes are accepted
  // (that is the point of the Figure 2 demonstration).
  Ccw16Interpolation(const Shape& shape, const Cage& cage, std::vector<Ccw16Keyframe> keyframes,
                     const Ccw16Options& options = {});

  // The frame at t evaluated on a rest mesh of the shape (hsi/triangulate.h): positions at its
  // vertices, integrated along the spanning tree's edges from the anchor.
  Ccw16Frame frame(double t, const TriMesh& mesh) const;
  Ccw16Mesh prepare(const TriMesh& mesh) const;
  Ccw16Frame frame(double t, const Ccw16Mesh& mesh) const;

  // f(t) along the polyline anchor() → path[0] → path[1] → …, which must stay inside the
  // shape: positions at the path's points (the last one's minus the first one's, on a closed
  // path around hole i, is n P_i). Also fills fz, fzbar and the distortions at those points.
  Ccw16Frame integrate_path(double t, std::span<const cd> path) const;

  double t_begin() const { return keys_.front().time; }
  double t_end() const { return keys_.back().time; }
  cd anchor() const { return anchor_; }
  int hole_count() const { return cage_.hole_count(); }
  // Per keyframe: max |ν_k| over the boundary samples (by the maximum principle, over Ω).
  const std::vector<double>& keyframe_max_nu() const { return key_max_nu_; }

 private:
  int segment(double t) const;
  void evaluate(std::span<const cd> points, Eigen::MatrixXcd& a, Eigen::MatrixXcd& b) const;

  Shape shape_;
  Cage cage_;
  std::vector<Ccw16Keyframe> keys_;
  Ccw16Options options_;
  double size_ = 1;
  cd anchor_;
  std::vector<cd> f_anchor_;          // f_k(anchor)
  std::vector<cd> lambda_anchor_;     // λ_k(anchor) on the chosen branch
  std::vector<double> key_max_nu_;
  Eigen::MatrixXcd phi_, psi_;        // (m + N) × keyframes
};

}  // namespace hsi::baselines
