// The CCW16 baseline (Chien, Chen & Weber 2016, "Bounded distortion harmonic shape
// interpolation", as our paper describes it in §1–2, Fig. 2 and Fig. 8): blend the
// keyframes' holomorphic derivatives, then integrate them. Not part of the product
// (issue #11): it is here to compare against, and to show that it breaks on shapes with
// holes. Two of CCW16's variants (Ccw16Variant): LogDerivatives, below, and
// BoundaryMetric, further down.
//
// ── Variant LogDerivatives (the default) ──────────────────────────────────────────────
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
//
// ── Variant BoundaryMetric (simply-connected shapes only) ─────────────────────────────
// The variant our paper's Fig. 8 compares with ("essentially solves a least square problem
// based on the Hilbert Transform"): the pull-back metric is blended on ∂Ω only, and the
// holomorphic derivatives inside are recovered from it. Reconstructed from our paper's
// account (§1, §4.1, §6 with Fig. 8), not from CCW16's text; the least-squares
// discretisation, the b fit and the rotation convention below are our choices.
//  1. At the boundary samples G, the keyframes' metrics (paper Eq. 5, hsi::pullback_metric)
//     blended linearly as our method blends them (Interpolator::blended_metric):
//         M(t) = (1 − s) M_k + s M_{k+1} = [[m1, m2], [m2, m3]].
//  2. With a = f_z = Φ', b = conj(f_zbar) = Ψ': m1 = S + 2 Re(ab), m2 = −2 Im(ab),
//     m3 = S − 2 Re(ab), S = |a|² + |b|² (math.md §4), so the metric determines
//         S = (m1 + m3)/2,   A := a·b = Φ'Ψ' = (m1 − m3)/4 − i m2/2,
//         σ1,2 = sqrt(S ± 2|A|),   |a| = (σ1 + σ2)/2,   |b| = (σ1 − σ2)/2,
//     i.e. |f_z|, |f_zbar| and arg(f_z conj(f_zbar)) = arg A; not arg f_z (the rotation).
//  3. Hilbert transform by least squares: L = log f_z = Σ_j C_j l_j, holomorphic, in the
//     Cauchy coordinates of the cage (hsi/basis.h; no log column, no hole), with
//         minimise Σ_G (Re L − log|a|)²      (uniform samples by arc length: the L² norm on ∂Ω)
//     which fixes L up to an imaginary constant (Σ_j C_j = 1: a global rotation). The constant
//     is chosen so that the mean of Im L over G is the LogDerivatives variant's:
//         mean_G arg a_k + s · mean_G Im λ_k   (λ_k's branch as above)
//     so the frame turns as CCW16's log blend does and is continuous in t. Then f_z = exp(L)
//     and Ψ' = A / f_z in phase with the metric's |b| in modulus,
//         b_G = |b| · e^{i (arg A − Im L)},
//     fitted by least squares by b = Σ_j D_j β_j (the keyframes' own space for conj f_zbar,
//     with β_0 = 0 against the constant null direction Σ_j D_j = 0).
//  4. The frame is integrated from a(t) = exp(L), b(t) = Σ D_j β_j exactly as above (same
//     anchor, translation, spanning tree and quadrature). a and b are holomorphic on the
//     simply-connected Ω, so the integral is path-independent (closure_error ≈ 0).
// At keyframe times the metric is the keyframe's and the fits reproduce it up to how well
// log f_z,k lies in the span of the Cauchy coordinates (frame.fit_*; on the bundled blob,
// 32 cage vertices: |f_z| within 2.1% at ∂Ω, positions within 7e-4 of the size). Between
// keyframes the blob's frames are within 3e-4 of the size of our interpolation's after a
// rigid alignment, against 0.09 for LogDerivatives (tests/test_ccw16.cpp). Where Ω has
// holes, Re L alone does not determine a single-valued L (the conjugate of a harmonic
// function has periods around each hole) and this Hilbert transform does not apply (our
// paper §1): the constructor refuses such a shape for this variant.
#pragma once

#include <array>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/QR>

#include "hsi/energy.h"
#include "hsi/harmonic_map.h"
#include "hsi/samples.h"
#include "hsi/triangulate.h"

namespace hsi::baselines {

struct Ccw16Keyframe {
  double time = 0;
  HarmonicMap map;  // over the scene's cage (hsi/harmonic_map.h)
};

enum class Ccw16Variant {
  LogDerivatives,  // log f_z and ν blended pointwise (works on any shape; tears around holes)
  BoundaryMetric,  // the metric blended on ∂Ω, f_z and f_zbar by a least-squares Hilbert transform (simply connected only)
};
const char* to_string(Ccw16Variant v);  // "log-derivatives" | "boundary-metric"

struct Ccw16Options {
  int samples = 10000;     // boundary samples: keyframes checked, λ's branch chosen, BoundaryMetric fitted
  int quadrature = 10;     // Gauss–Legendre nodes per piece
  double max_piece = 0.025;  // longest straight piece integrated at once, relative to the shape's diagonal
  Ccw16Variant variant = Ccw16Variant::LogDerivatives;
};

struct Ccw16Frame {
  double t = 0;
  std::vector<cd> positions;        // f at the requested points (rest positions), integrated from the anchor
  std::vector<cd> fz, fzbar;        // f_z = a(t), f_zbar = conj(b(t)) at those points
  std::vector<double> hole_period;  // per hole: |P_i| (0 = integrable); empty when simply connected
  double max_kappa = 1, max_isometric = 2;  // over the points: κ = (|f_z|+|f_zbar|)/(|f_z|−|f_zbar|), ½(σ1²+σ1⁻²+σ2²+σ2⁻²)
  double max_nu = 0;                // over the points: |ν(t)| = |f_zbar| / |f_z|

  // BoundaryMetric only (0 for LogDerivatives): how well the fitted a(t), b(t) realise the
  // blended metric at the boundary samples G, maxima over G.
  double fit_log_modulus = 0;   // |Re L − log|a|_M|: relative error of |f_z|
  double fit_fzbar = 0;         // |b − b_G| / |a|_M: error of conj f_zbar relative to |f_z|
  double fit_metric = 0;        // ‖M(a, b) − M(t)‖_F / ‖M(t)‖_F

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
  Eigen::MatrixXcd C_, D_;            // BoundaryMetric only: basis rows at every point (points × m)
};

class Ccw16Interpolation {
 public:
  // ≥ 2 keyframes, increasing finite times, maps of the cage's size with ψ_log = conj φ_log,
  // each locally injective at the boundary samples (f_z ≠ 0, |ν| < 1, and f_z without zeros in
  // Ω by the argument principle), consecutive keyframes with f_z winding equally around every
  // hole; else InputError naming the keyframe and the problem. Shapes with holes are accepted
  // by LogDerivatives (that is the point of the Figure 2 demonstration) and refused by
  // BoundaryMetric (InputError: its Hilbert transform needs a simply-connected domain).
  Ccw16Interpolation(const Shape& shape, const Cage& cage, std::vector<Ccw16Keyframe> keyframes,
                     const Ccw16Options& options = {});

  // The frame at t evaluated on a rest mesh of the shape (hsi/triangulate.h): positions at its
  // vertices, integrated along the spanning tree's edges from the anchor.
  Ccw16Frame frame(double t, const TriMesh& mesh) const;
  // BoundaryMetric keeps the C and D basis rows at every vertex and Gauss node (2 × 16 bytes
  // × m per point: ~60 MB for a 2,000-vertex mesh of a 32-vertex cage, ~300 MB at 10,000
  // vertices), so that a frame costs a matrix–vector product, not a basis evaluation.
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
  Ccw16Variant variant() const { return options_.variant; }
  // Per keyframe: max |ν_k| over the boundary samples (by the maximum principle, over Ω).
  const std::vector<double>& keyframe_max_nu() const { return key_max_nu_; }

 private:
  // BoundaryMetric: the holomorphic L = log f_z = Σ C_j l_j and b = Σ D_j β_j fitted at G.
  struct BoundaryFit {
    VectorXcd l, beta;
    double log_modulus = 0, fzbar = 0, metric = 0;  // the residuals of Ccw16Frame::fit_*
  };
  int segment(double t) const;
  double blend_parameter(int k, double t) const;
  void evaluate(std::span<const cd> points, Eigen::MatrixXcd& a, Eigen::MatrixXcd& b) const;
  BoundaryFit fit_boundary(int k, double s) const;
  void prepare_boundary_fit(const BoundarySamples& G, const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b);

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

  // BoundaryMetric: the keyframes' metrics at G, the two least-squares factorisations (their
  // matrices do not depend on t), and the rotation reference per keyframe / segment.
  std::vector<std::vector<Metric>> key_metrics_;  // keyframes × |G|
  Eigen::MatrixXcd C_G_, D_G_;                    // basis rows at G
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> fit_L_;   // [Re C, −Im C; mean Im C, mean Re C] (|G| + 1) × 2m
  Eigen::ColPivHouseholderQR<Eigen::MatrixXcd> fit_b_;  // D without column 0, |G| × (m − 1)
  std::vector<double> key_mean_arg_;    // mean over G of arg a_k (unwrapped along ∂Ω)
  std::vector<double> lambda_mean_arg_; // mean over G of Im λ_k on the chosen branch
};

}  // namespace hsi::baselines
