// Cauchy coordinates of a multiply-connected cage (WBCG10, CW17; math.md §2).
#include "hsi/basis.h"

#include <cmath>
#include <numbers>

namespace hsi {

int Cage::vertex_count() const {
  int m = 0;
  for (const Loop& l : loops) m += static_cast<int>(l.size());
  return m;
}

int Cage::loop_offset(int k) const {
  int m = 0;
  for (int i = 0; i < k; ++i) m += static_cast<int>(loops[static_cast<size_t>(i)].size());
  return m;
}

BasisRows evaluate_basis(const Cage& cage, std::span<const cd> points, unsigned parts) {
  const int m = cage.vertex_count();
  const int cols = m + cage.hole_count();
  const Eigen::Index P = static_cast<Eigen::Index>(points.size());
  BasisRows r;
  const bool wantC = parts & kBasisC, wantD = parts & kBasisD, wantE = parts & kBasisE;
  if (wantC) r.C.resize(P, cols);
  if (wantD) r.D.resize(P, cols);
  if (wantE) r.E.resize(P, cols);
  const cd inv2pii = 1.0 / (2.0 * std::numbers::pi * cd(0, 1));

#pragma omp parallel for schedule(static)
  for (Eigen::Index p = 0; p < P; ++p) {
    const cd w = points[static_cast<size_t>(p)];
    int col = 0;
    std::vector<cd> B, L;  // per loop: B_j = z_j − w, L_j = log(B_{j+1}/B_j) (edge j → j+1)
    for (const Loop& loop : cage.loops) {
      const int k = static_cast<int>(loop.size());
      B.resize(static_cast<size_t>(k));
      L.resize(static_cast<size_t>(k));
      for (int j = 0; j < k; ++j) B[static_cast<size_t>(j)] = loop[static_cast<size_t>(j)] - w;
      for (int j = 0; j < k; ++j) L[static_cast<size_t>(j)] = std::log(B[static_cast<size_t>((j + 1) % k)] / B[static_cast<size_t>(j)]);
      for (int j = 0; j < k; ++j) {
        const size_t jm = static_cast<size_t>((j + k - 1) % k), j0 = static_cast<size_t>(j), jp = static_cast<size_t>((j + 1) % k);
        const cd A0 = loop[j0] - loop[jm];  // A_j
        const cd A1 = loop[jp] - loop[j0];  // A_{j+1}
        // L[jm] = log(B_j / B_{j−1}), L[j0] = log(B_{j+1} / B_j)
        if (wantC) r.C(p, col + j) = inv2pii * (B[jp] / A1 * L[j0] - B[jm] / A0 * L[jm]);
        if (wantD) r.D(p, col + j) = inv2pii * (L[jm] / A0 - L[j0] / A1);
        if (wantE) r.E(p, col + j) = inv2pii * (B[jp] - B[jm]) / (B[jm] * B[j0] * B[jp]);
      }
      col += k;
    }
    for (int h = 0; h < cage.hole_count(); ++h) {
      const cd d = w - cage.hole_points[static_cast<size_t>(h)];
      if (wantC) r.C(p, m + h) = std::log(std::abs(d));
      if (wantD) r.D(p, m + h) = 1.0 / d;
      if (wantE) r.E(p, m + h) = -1.0 / (d * d);
    }
  }
  return r;
}

}  // namespace hsi
