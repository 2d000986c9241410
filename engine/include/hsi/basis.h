// The harmonic map basis (math.md §2): Cauchy coordinates C_j of every cage vertex
// (CW17's discretisation of the paper's Eq. 2 and 4) plus one log|w − ρ_i| column
// per hole, and their derivatives D = C' and E = D'.
//
// Column layout ("full" basis, size m + N): the cage vertices loop by loop (outer
// loop first), then one column per hole.
#pragma once

#include <Eigen/Core>
#include <span>

#include "hsi/cage.h"

namespace hsi {

using MatrixXcd = Eigen::MatrixXcd;
using VectorXcd = Eigen::VectorXcd;

inline int basis_size(const Cage& cage) { return cage.vertex_count() + cage.hole_count(); }

struct BasisRows {
  MatrixXcd C, D, E;  // points × (m + N); an empty matrix where not requested
};

enum BasisPart : unsigned { kBasisC = 1u, kBasisD = 2u, kBasisE = 4u, kBasisAll = 7u };

// Evaluates the requested rows at every point w (none may lie on the cage or at a
// hole point). Multi-threaded over points.
BasisRows evaluate_basis(const Cage& cage, std::span<const cd> points, unsigned parts = kBasisAll);

}  // namespace hsi
