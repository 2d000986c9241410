// Harmonic maps over the CW17 basis: evaluation and the maps every test starts from.
#include "hsi/harmonic_map.h"

namespace hsi {

HarmonicMap identity_map(const Cage& cage) { return affine_map(cage, 1.0, 0.0, 0.0); }

HarmonicMap affine_map(const Cage& cage, cd a, cd b, cd c) {
  // Cauchy coordinates reproduce holomorphic linear functions: Φ(w) = a w + c from
  // φ_j = a z_j + c, and conj(Ψ) = b conj(w) from ψ_j = conj(b) z_j.
  const int m = cage.vertex_count();
  HarmonicMap map{VectorXcd::Zero(basis_size(cage)), VectorXcd::Zero(basis_size(cage))};
  int j = 0;
  for (size_t l = 0; l < cage.loops.size(); ++l)
    for (const cd& z : cage.loops[l]) {
      map.phi(j) = a * z + (l == 0 ? c : cd(0));
      map.psi(j) = std::conj(b) * z;
      ++j;
    }
  (void)m;
  return map;
}

MapValues evaluate_map(const BasisRows& rows, const HarmonicMap& map) {
  MapValues v;
  if (rows.C.size()) v.f = rows.C * map.phi + (rows.C * map.psi).conjugate();
  if (rows.D.size()) {
    v.f_z = rows.D * map.phi;
    v.fzbar_conj = rows.D * map.psi;
  }
  if (rows.E.size()) v.f_zz = rows.E * map.phi;
  return v;
}

MapValues evaluate_map(const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
  return evaluate_map(evaluate_basis(cage, points), map);
}

HarmonicMap transform_image(const Cage& cage, const HarmonicMap& map, cd r, cd t) {
  HarmonicMap out{r * map.phi, std::conj(r) * map.psi};
  // ψ_log = conj φ_log is kept: conj(r φ) = conj(r) conj(φ).
  for (int j = 0; j < static_cast<int>(cage.loops.front().size()); ++j) out.phi(j) += t;
  return out;
}

}  // namespace hsi
