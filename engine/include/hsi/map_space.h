// The reduced variables of math.md §3 (paper §5.3): the coefficients over-describe
// the map, and the Newton solver works on a real vector x with no redundancy.
//
// Active columns: all outer-loop vertices, every hole-loop vertex but the first two
// of that loop (each hole loop's Cauchy integral of a + b w vanishes outside it), and
// the N hole columns: n = m_outer + Σ (m_hole − 2) + N. φ and ψ share the same
// active columns, so one complex row D(w) serves both.
//
// The active real vector is v = (Re φ_a, Im φ_a, Re ψ_a, Im ψ_a) ∈ R^{4n} (the
// paper's Appendix B order) and v = T x with the remaining constraints built in:
//   ψ_log = conj φ_log (per hole), ψ_0 = 0 at outer vertex 0 (Φ and conj Ψ share
//   constants); in the ModuloRigid gauge also φ_0 = 0 (translation) and
//   Re φ_r = 0 (rotation; the paper's Re φ_1 = 0, with r the outer vertex farthest
//   from vertex 0 so that the rotation is pinned firmly), since the interpolation
//   energy sees only f_z and conj f_zbar.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

#include "hsi/harmonic_map.h"

namespace hsi {

enum class Gauge {
  Map,    // x determines f exactly: dim = 4n − 2N − 2
  ModuloRigid  // x determines f up to a rigid motion: dim = 4n − 2N − 5
};

class MapSpace {
 public:
  MapSpace(const Cage& cage, Gauge gauge);

  Gauge gauge() const { return gauge_; }
  int full_size() const { return full_size_; }        // m + N
  int n() const { return static_cast<int>(active_.size()); }
  int dim() const { return static_cast<int>(T_.cols()); }
  const std::vector<int>& active() const { return active_; }  // active full-column indices
  int rotation_vertex() const { return rotation_vertex_; }
  const Eigen::SparseMatrix<double>& T() const { return T_; } // 4n × dim, entries ±1

  // Restricts full basis rows to the active columns.
  MatrixXcd restrict_columns(const MatrixXcd& full_rows) const;

  // x ↦ map (full coefficients; dropped hole vertices are 0).
  HarmonicMap expand(const Eigen::VectorXd& x) const;

  // An equivalent map in this gauge: for Gauge::Map the same f exactly; for
  // Gauge::ModuloRigid f_original(w) = rotation · f_canonical(w) + translation, |rotation| = 1.
  struct Canonical {
    Eigen::VectorXd x;
    cd rotation{1.0, 0.0};
    cd translation{0.0, 0.0};
  };
  // Throws InputError if ψ_log ≠ conj φ_log beyond a relative 1e-9.
  Canonical reduce(const HarmonicMap& map) const;

  // The global rotation of the image, φ → e^{iθ}φ, ψ → e^{−iθ}ψ, differentiated at
  // θ = 0, at active coefficients v = T x (4n): (−Im φ, Re φ, Im ψ, −Re ψ). It keeps
  // every constraint of the space but the rotation gauge Re φ_r = 0, and the
  // interpolation energy and the certificate are invariant along the rotation.
  Eigen::VectorXd rotation_generator(const Eigen::VectorXd& v) const;
  // ModuloRigid only: active coefficients v that satisfy every constraint but the
  // rotation gauge (v = T x + c·rotation_generator(T x), say) turned back into the gauge
  // by the exact rotation of the image that puts φ_r on the positive imaginary axis,
  // and read off as x. The map changes by that rigid rotation alone.
  Eigen::VectorXd regauge(const Eigen::VectorXd& v) const;
  // Row of T holding each column's free variable (its first, +1 entry): x(c) = v(row).
  const std::vector<int>& primary_rows() const { return primary_rows_; }

 private:
  Gauge gauge_;
  int full_size_ = 0;
  int outer_vertices_ = 0;
  int rotation_vertex_ = 1;                   // outer vertex whose Re φ is fixed (ModuloRigid)
  std::vector<int> active_;
  std::vector<std::vector<int>> hole_loops_;  // full indices of each hole loop's vertices
  std::vector<cd> hole_vertices_;             // their positions (same order, flattened per hole)
  std::vector<int> log_columns_;              // active indices of the hole columns
  Eigen::SparseMatrix<double> T_;
  std::vector<cd> cage_vertices_;
  std::vector<int> primary_rows_;
};

}  // namespace hsi

namespace hsi {

// The real-linear map from reduced x to values at points: f (Gauge::Map) or
// (f_z, conj f_zbar) (Gauge::ModuloRigid), as a real matrix with rows
// (Re, Im) per point and value. Its full column rank is what makes the
// reduction free of redundancy (math.md §3).
Eigen::MatrixXd reduced_evaluation_matrix(const MapSpace& space, const BasisRows& full_rows);

struct Conditioning {
  double sigma_min = 0, sigma_max = 0;
  int rows = 0, cols = 0;
};
Conditioning conditioning(const MapSpace& space, const BasisRows& full_rows);

}  // namespace hsi
