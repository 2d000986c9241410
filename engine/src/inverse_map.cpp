// The inverse of a map at a point: the triangle whose image holds it, then Newton on f.
#include "hsi/inverse_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hsi {

InverseMap::InverseMap(const Shape& shape, const Cage& cage, const InverseMapOptions& options)
    : cage_(cage), options_(options) {
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(shape, options.mesh_vertices);
  mesh_ = triangulate(shape, to);
  rows_ = evaluate_basis(cage_, mesh_.vertices, kBasisC);
  const BoundingBox b = bounding_box(shape);
  size_ = std::abs(b.hi - b.lo);
}

std::optional<cd> InverseMap::rest_point(const HarmonicMap& map, cd image) {
  if (!map_ || map_->phi.size() != map.phi.size() || map_->phi != map.phi || map_->psi != map.psi) {
    f_ = evaluate_map(rows_, map).f;
    map_ = map;
  }
  const auto& V = mesh_.vertices;
  for (const auto& t : mesh_.triangles) {
    const cd a = f_(t[0]), b = f_(t[1]), c = f_(t[2]);
    const double det = (b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real();
    if (std::abs(det) < 1e-300) continue;
    const cd p = image - a;
    const double u = (p.real() * (c - a).imag() - p.imag() * (c - a).real()) / det;
    const double v = ((b - a).real() * p.imag() - (b - a).imag() * p.real()) / det;
    if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9) continue;
    const cd z0 = V[static_cast<size_t>(t[0])], z1 = V[static_cast<size_t>(t[1])], z2 = V[static_cast<size_t>(t[2])];
    const cd guess = z0 + u * (z1 - z0) + v * (z2 - z0);
    // Newton on f(z) = image: f(z + dz) ≈ f + f_z dz + f_z̄ conj(dz), solved for dz in
    // closed form; |f_z| > |f_z̄| where the map is locally injective (math.md §3).
    const double reach = 2 * std::max({std::abs(z1 - z0), std::abs(z2 - z1), std::abs(z0 - z2)});
    cd z = guess, best = guess;
    double best_r = std::numeric_limits<double>::infinity();
    for (int step = 0; step <= options_.newton_steps; ++step) {
      const MapValues m = evaluate_map(cage_, map, std::span<const cd>(&z, 1));
      const cd r = image - m.f(0);
      if (std::abs(r) < best_r) {
        best_r = std::abs(r);
        best = z;
      }
      if (best_r <= 1e-15 * size_ || step == options_.newton_steps) break;
      const cd fz = m.f_z(0), fzbar = std::conj(m.fzbar_conj(0));
      const double jac = std::norm(fz) - std::norm(fzbar);
      if (!(jac > 0)) break;
      const cd dz = (std::conj(fz) * r - fzbar * std::conj(r)) / jac;
      if (!std::isfinite(dz.real()) || !std::isfinite(dz.imag()) || std::abs(z + dz - guess) > reach) break;
      z += dz;
    }
    return best;
  }
  return std::nullopt;
}

}  // namespace hsi
