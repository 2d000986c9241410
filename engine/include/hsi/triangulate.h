// A triangulation of the shape Ω with its holes (CGAL's constrained Delaunay mesher):
// the render mesh that the renderer draws, glTF exports and the baked runtime's
// examples deform. Boundary vertices lie exactly on the shape's edges, so the
// deformed mesh's outline is the map of the shape's outline.
#pragma once

#include <array>
#include <vector>

#include "hsi/domain.h"

namespace hsi {

struct TriangulateOptions {
  // Target edge length inside the shape and on its boundary (≤ 0: the bounding box
  // diagonal / 40). edge_for_vertex_count() turns a vertex budget into this.
  double max_edge = 0;
  // Quality bound of the mesher (CGAL's B = 1 / (4 sin² θ)): 0.125 ⇔ angles ≥ 20.7°.
  double shape_bound = 0.125;
  // Refuse meshes expected to exceed this many vertices (InputError) instead of
  // exhausting memory on a mistyped resolution.
  int max_vertices = 20'000'000;
};

struct TriMesh {
  std::vector<cd> vertices;                  // rest positions in the shape's plane
  // Counter-clockwise, in Hilbert-curve order of their rest centroids: spatially
  // coherent, so where a map overlaps itself the renderers' "later triangle on top"
  // rule shows each layer in whole patches (issue #20).
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> boundary_loop;            // per vertex: loop index (0 outer, k hole k−1), −1 inside
  // Boundary edges (a, b) with the shape on their left, grouped by loop.
  std::vector<std::array<int, 2>> boundary_edges;

  int vertex_count() const { return static_cast<int>(vertices.size()); }
  int triangle_count() const { return static_cast<int>(triangles.size()); }
};

// Throws InputError if the shape is invalid (validate()) or the mesh would be too large.
TriMesh triangulate(const Shape& shape, const TriangulateOptions& options = {});

// The max_edge that gives roughly `vertices` vertices for this shape (near-equilateral
// triangles of that edge cover area(shape) with about that many vertices).
double edge_for_vertex_count(const Shape& shape, int vertices);

}  // namespace hsi
