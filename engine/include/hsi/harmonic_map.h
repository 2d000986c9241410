// A harmonic map in the CW17 space (paper Eq. 2–4): complex coefficients φ, ψ over
// the full basis (m cage vertices, then N hole columns with ψ_log = conj φ_log).
//   f(w) = Σ C_j φ_j + conj(Σ C_j ψ_j),  f_z = Σ D_j φ_j,
//   conj(f_zbar) = Σ D_j ψ_j,            f_zz = Σ E_j φ_j.
#pragma once

#include "hsi/basis.h"

namespace hsi {

struct HarmonicMap {
  VectorXcd phi, psi;  // size m + N
};

// φ_j = z_j, ψ = 0: f(w) = w everywhere inside the cage domain.
HarmonicMap identity_map(const Cage& cage);
// f(w) = a w + b conj(w) + c, exactly (for any complex a, b, c).
HarmonicMap affine_map(const Cage& cage, cd a, cd b, cd c);

struct MapValues {
  VectorXcd f, f_z, fzbar_conj, f_zz;  // per point; empty where the rows were not given
};

// Evaluates the map from precomputed basis rows (any subset of C, D, E).
MapValues evaluate_map(const BasisRows& rows, const HarmonicMap& map);
// Convenience: evaluates the rows at the points first.
MapValues evaluate_map(const Cage& cage, const HarmonicMap& map, std::span<const cd> points);

// Applies the rigid (or similarity) motion w ↦ r w + t to the image: φ ↦ r φ + t on
// the outer-loop constant direction, ψ ↦ conj(r) ψ, so f ↦ r f + t.
HarmonicMap transform_image(const Cage& cage, const HarmonicMap& map, cd r, cd t);

}  // namespace hsi
