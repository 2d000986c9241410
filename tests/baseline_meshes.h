// Meshes, maps and checks the mesh-baseline tests share (ARAP, FFMP, GE): the bar with
// holes as a mesh, maps applied to a mesh, distances and centroids, and the message of
// an expected InputError.
#pragma once

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "hsi/triangulate.h"
#include "test_shapes.h"

namespace hsi::test::mesh {

// The bar with three holes, centred at the origin.
inline TriMesh bar_mesh(int vertices) {
  Shape s = test::bar_with_holes();
  for (int l = 0; l < s.loop_count(); ++l)
    for (cd& p : s.loop(l)) p -= cd(2, 0.5);
  return triangulate(s, {.max_edge = edge_for_vertex_count(s, vertices)});
}

inline double mesh_size(const TriMesh& m) {
  cd lo = m.vertices[0], hi = m.vertices[0];
  for (cd p : m.vertices) {
    lo = {std::min(lo.real(), p.real()), std::min(lo.imag(), p.imag())};
    hi = {std::max(hi.real(), p.real()), std::max(hi.imag(), p.imag())};
  }
  return std::abs(hi - lo);
}

inline std::vector<cd> apply(const TriMesh& m, const std::function<cd(cd)>& f) {
  std::vector<cd> x;
  for (cd z : m.vertices) x.push_back(f(z));
  return x;
}

inline double signed_area(std::span<const cd> x, const std::array<int, 3>& t) {
  return 0.5 * std::imag(std::conj(x[static_cast<size_t>(t[1])] - x[static_cast<size_t>(t[0])]) * (x[static_cast<size_t>(t[2])] - x[static_cast<size_t>(t[0])]));
}

// Area-weighted centroid of the mesh under positions x: Σ_T area_T · centroid_T / Σ area_T,
// with the rest areas (computed here independently of the library's lumped masses).
inline cd centroid(const TriMesh& m, std::span<const cd> x) {
  cd sum = 0;
  double total = 0;
  for (const auto& t : m.triangles) {
    const double a = signed_area(m.vertices, t);
    sum += a * (x[static_cast<size_t>(t[0])] + x[static_cast<size_t>(t[1])] + x[static_cast<size_t>(t[2])]) / 3.0;
    total += a;
  }
  return sum / total;
}

inline double max_distance(std::span<const cd> a, std::span<const cd> b) {
  REQUIRE(a.size() == b.size());
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

// A conformal bend of the bar: the tangent turns by `b` radians per unit of x.
inline cd bend(cd z, double b) { return std::abs(b) < 1e-12 ? z : (std::exp(cd(0, b) * z) - 1.0) / cd(0, b); }

inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  FAIL("no InputError was thrown");
  return "";
}

}  // namespace hsi::test::mesh
