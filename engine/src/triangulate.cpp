// Triangulation of a shape with holes: CGAL's constrained Delaunay triangulation of
// the (edge-subdivided) loops, refined by the Delaunay mesher with the holes seeded
// out. CGAL lives in this TU and in cgal_geometry.cpp only.
#include "hsi/triangulate.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

namespace hsi {
namespace {
struct VertexInfo {
  int loop = -1;   // loop the vertex was inserted on (−1: a Steiner point)
  int index = -1;  // output index
};
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexInfo, K>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;
using Point = K::Point_2;

// Position of (x, y) along the Hilbert curve over an n × n grid (n a power of two).
uint64_t hilbert_index(uint32_t n, uint32_t x, uint32_t y) {
  uint64_t d = 0;
  for (uint32_t s = n / 2; s > 0; s /= 2) {
    const uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
    d += uint64_t{s} * s * ((3u * rx) ^ ry);
    if (ry == 0) {
      if (rx == 1) {
        x = n - 1 - x;
        y = n - 1 - y;
      }
      std::swap(x, y);
    }
  }
  return d;
}

// Triangles in Hilbert-curve order of their rest centroids (CGAL's face order is its
// memory order, scattered over the shape). Where a map overlaps itself, both
// rasterizers draw the later triangle in this order on top (issue #20): in a
// spatially coherent order each layer wins in whole patches, not in a speckle of
// alternating triangles. Deterministic (ties keep CGAL's order).
void sort_triangles_spatially(TriMesh& mesh) {
  if (mesh.triangles.size() < 2) return;
  BoundingBox bb{mesh.vertices.front(), mesh.vertices.front()};
  for (const cd& v : mesh.vertices) {
    bb.lo = {std::min(bb.lo.real(), v.real()), std::min(bb.lo.imag(), v.imag())};
    bb.hi = {std::max(bb.hi.real(), v.real()), std::max(bb.hi.imag(), v.imag())};
  }
  constexpr uint32_t n = 1u << 16;
  const double side = std::max({bb.hi.real() - bb.lo.real(), bb.hi.imag() - bb.lo.imag(), 1e-300});
  auto cell = [&](double t) { return static_cast<uint32_t>(std::clamp(t / side * n, 0.0, n - 1.0)); };
  std::vector<uint64_t> key(mesh.triangles.size());
  for (size_t t = 0; t < key.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const cd c = (mesh.vertices[static_cast<size_t>(tri[0])] + mesh.vertices[static_cast<size_t>(tri[1])] +
                  mesh.vertices[static_cast<size_t>(tri[2])]) / 3.0;
    key[t] = hilbert_index(n, cell(c.real() - bb.lo.real()), cell(c.imag() - bb.lo.imag()));
  }
  std::vector<size_t> order(key.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return key[a] < key[b]; });
  std::vector<std::array<int, 3>> sorted;
  sorted.reserve(order.size());
  for (size_t t : order) sorted.push_back(mesh.triangles[t]);
  mesh.triangles = std::move(sorted);
}

// Vertices per unit area for near-equilateral triangles of edge h (2 triangles per vertex).
double vertex_density(double h) { return 2.0 / (std::sqrt(3.0) * h * h); }
}  // namespace

double edge_for_vertex_count(const Shape& shape, int vertices) {
  if (vertices < 3) throw InputError("triangulate: a vertex budget of " + std::to_string(vertices) + " is too small");
  // V ≈ a / h² (interior: the mesher's size bound is an upper bound on edges, so its
  // meshes come out about twice as dense than equilateral ones) + b / h (the
  // boundary's extra vertices, which dominate small budgets); solved for 1 / h.
  double boundary = 0;
  for (int l = 0; l < shape.loop_count(); ++l) boundary += perimeter(shape.loop(l));
  const double a = 2.0 * area(shape) * vertex_density(1.0), b = boundary;
  const double x = (-b + std::sqrt(b * b + 4 * a * vertices)) / (2 * a);
  return 1 / x;
}

TriMesh triangulate(const Shape& input, const TriangulateOptions& options) {
  validate(input);
  const Shape shape = normalize(input);
  const double h = options.max_edge > 0 ? options.max_edge : bounding_box(shape).diagonal() / 40;
  if (!std::isfinite(h)) throw InputError("triangulate: max_edge must be finite");
  const double expected = 1.6 * area(shape) * vertex_density(h);
  if (expected > options.max_vertices)
    throw InputError("triangulate: max_edge " + std::to_string(h) + " would give about " +
                     std::to_string(static_cast<long long>(expected)) + " vertices (limit " +
                     std::to_string(options.max_vertices) + ")");

  CDT cdt;
  std::vector<CDT::Vertex_handle> first(static_cast<size_t>(shape.loop_count()));
  for (int l = 0; l < shape.loop_count(); ++l) {
    const Loop loop = subdivide_edges(shape.loop(l), h);
    std::vector<CDT::Vertex_handle> vh;
    vh.reserve(loop.size());
    for (const cd& p : loop) {
      auto v = cdt.insert(Point(p.real(), p.imag()));
      v->info().loop = l;
      vh.push_back(v);
    }
    for (size_t i = 0; i < vh.size(); ++i) cdt.insert_constraint(vh[i], vh[(i + 1) % vh.size()]);
    first[static_cast<size_t>(l)] = vh.front();
  }
  std::vector<Point> seeds;
  for (const Loop& hole : shape.holes) {
    const cd c = largest_inscribed_circle(hole).center;
    seeds.emplace_back(c.real(), c.imag());
  }
  Mesher mesher(cdt, Criteria(options.shape_bound, h));
  mesher.set_seeds(seeds.begin(), seeds.end(), /*mark=*/false);
  mesher.refine_mesh();

  TriMesh mesh;
  auto index_of = [&](CDT::Vertex_handle v) {
    if (v->info().index < 0) {
      v->info().index = mesh.vertex_count();
      mesh.vertices.emplace_back(v->point().x(), v->point().y());
      mesh.boundary_loop.push_back(v->info().loop);
    }
    return v->info().index;
  };
  // next[a] = b for each boundary edge a → b (shape on the left).
  std::vector<int> next;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (!f->is_in_domain()) continue;
    mesh.triangles.push_back({index_of(f->vertex(0)), index_of(f->vertex(1)), index_of(f->vertex(2))});
    for (int i = 0; i < 3; ++i) {
      const auto g = f->neighbor(i);
      if (!cdt.is_infinite(g) && g->is_in_domain()) continue;
      const int a = index_of(f->vertex(CDT::ccw(i))), b = index_of(f->vertex(CDT::cw(i)));
      if (next.size() < mesh.vertices.size()) next.resize(mesh.vertices.size(), -1);
      next[static_cast<size_t>(a)] = b;
    }
  }
  next.resize(mesh.vertices.size(), -1);
  // Walk each loop from one of its own vertices: orders the edges and gives Steiner
  // points on the boundary their loop.
  for (int l = 0; l < shape.loop_count(); ++l) {
    const int start = first[static_cast<size_t>(l)]->info().index;
    if (start < 0) throw InputError("triangulate: " + loop_name(l) + " is not on the mesh's boundary");
    int a = start;
    do {
      const int b = next[static_cast<size_t>(a)];
      if (b < 0) throw InputError("triangulate: the mesh boundary along " + loop_name(l) + " is not closed");
      mesh.boundary_edges.push_back({a, b});
      mesh.boundary_loop[static_cast<size_t>(b)] = l;
      a = b;
    } while (a != start && mesh.boundary_edges.size() <= mesh.vertices.size());
  }
  // Interior vertices keep −1 even if inserted on a loop (cannot happen for valid shapes).
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (next[v] < 0) mesh.boundary_loop[v] = -1;
  sort_triangles_spatially(mesh);
  return mesh;
}

}  // namespace hsi
