// What the mesh baselines (ARAP, FFMP, GE) share, private to hsi_baselines: checked rest
// triangles with their Jacobian operators, keyframe checks, connected components with
// lumped masses, the factorised Poisson system that turns per-triangle target
// Jacobians into positions, and a sparse matrix whose pattern is fixed once per mesh.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <array>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "hsi/baselines/mesh_keyframe.h"
#include "hsi/triangulate.h"

namespace hsi::baselines::detail {

using Mat2 = Eigen::Matrix2d;

inline size_t at(int i) { return static_cast<size_t>(i); }

std::string num(double x);
std::string point(cd p);
std::string triangle_name(int t, const std::array<int, 3>& v);

// The representative of x mod 2π in [−π, π].
double wrap(double x);
// [b − a, c − a] as columns: the triangle's edge matrix.
Mat2 edge_matrix(cd a, cd b, cd c);
// Polar angle of J (the rotation nearest J): arg f_z, with J acting as z ↦ f_z z + f_z̄ z̄.
double polar_angle(const Mat2& J);
Mat2 rotation(double angle);

struct RestTriangle {
  std::array<int, 3> v{};
  double area = 0;
  Mat2 E_inv;  // inverse rest edge matrix: rows are ∇φ of v[1] and v[2]; ∇φ of v[0] is minus their sum
  // ∇φ of v[0], v[1], v[2] (the rest gradients of the hat functions).
  std::array<Eigen::Vector2d, 3> gradients() const;
};

// Throws InputError naming a non-finite vertex, a missing or out-of-range index, a
// repeated vertex or a degenerate triangle.
std::vector<RestTriangle> rest_triangles(const TriMesh& rest);
void check_positions(const TriMesh& rest, std::span<const cd> positions, const std::string& what);
// The Jacobian of the piecewise-linear map rest → x on T.
Mat2 jacobian(const RestTriangle& T, std::span<const cd> x);

// ≥ 2 keyframes at strictly increasing finite times with rest.vertex_count() finite
// positions each; `method` names the baseline in the messages ("FFMP keyframe 1 (t = 2)").
void check_keyframes(const TriMesh& rest, std::span<const MeshKeyframe> keyframes, const std::string& method);
std::string keyframe_name(const std::string& method, size_t k, double time);
// Every keyframe Jacobian has det J > 0, else InputError naming the keyframe, the triangle
// and `why` (what the method needs it for).
void check_orientation(std::span<const RestTriangle> tris, std::span<const MeshKeyframe> keyframes, const std::string& method,
                       const std::string& why);

// The keyframe segment k and local parameter s ∈ [0, 1] of time t (clamped to the
// keyframes' range; InputError naming `method` for NaN).
std::pair<int, double> locate(std::span<const double> times, double t, const std::string& method);

// Connected components of the mesh (triangles sharing a vertex) with lumped masses.
struct MeshComponents {
  std::vector<int> component;         // per vertex
  std::vector<double> mass;           // per vertex: a third of its triangles' rest area
  std::vector<double> component_mass;
  int count() const { return static_cast<int>(component_mass.size()); }
  // Per component: its area-weighted centroid under positions x (lumped masses).
  std::vector<cd> centroids(std::span<const cd> x) const;
  // Translate each component of x so that its centroid is target[c].
  void move_centroids(std::vector<cd>& x, std::span<const cd> target) const;
};
// Throws InputError for a vertex in no triangle.
MeshComponents mesh_components(int vertex_count, std::span<const RestTriangle> tris);

// x minimises Σ_T area_T ‖J_T(x) − A_T‖²_F: two Poisson problems (one per coordinate)
// with the cotangent stiffness matrix, factorised once (SimplicialLDLT, the first vertex
// of each component pinned). The result is fixed up to a translation per component: the
// caller places the centroids (MeshComponents::move_centroids).
class PoissonSolver {
 public:
  // `method` names the baseline in the message if the system cannot be factorised.
  PoissonSolver(int vertex_count, std::span<const RestTriangle> tris, const MeshComponents& components,
                const std::string& method);
  std::vector<cd> solve(std::span<const RestTriangle> tris, std::span<const Mat2> A) const;
  // Σ_T area_T ‖J_T(x) − A_T‖²_F.
  static double energy(std::span<const RestTriangle> tris, std::span<const Mat2> A, std::span<const cd> x);

 private:
  int n_ = 0;
  std::vector<int> reduced_;  // per vertex: row in the pinned system, −1 if pinned
  int reduced_count_ = 0;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
};

// A symmetric sparse matrix whose pattern is fixed once (per mesh): entries are added
// by their slot, so assembling a new matrix of the same pattern costs no search and the
// factorisation's symbolic analysis is done once.
class FixedPattern {
 public:
  // The (row, column) pairs that may be non-zero (duplicates allowed).
  FixedPattern(int size, std::span<const std::pair<int, int>> entries);
  // The slot of entry (row, column), which must be in the pattern.
  int slot(int row, int column) const;
  Eigen::SparseMatrix<double>& matrix() { return matrix_; }
  const Eigen::SparseMatrix<double>& matrix() const { return matrix_; }
  double* values() { return matrix_.valuePtr(); }
  void zero();

 private:
  Eigen::SparseMatrix<double> matrix_;
};

}  // namespace hsi::baselines::detail
