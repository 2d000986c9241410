// The render mesh: covers the shape exactly (area, boundary on the loops, nothing in
// the holes), respects the size and angle bounds, and its boundary walks each loop.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "hsi/triangulate.h"
#include "test_shapes.h"

using namespace hsi;

namespace {
double tri_area(const TriMesh& m, const std::array<int, 3>& t) {
  const cd a = m.vertices[static_cast<size_t>(t[0])], b = m.vertices[static_cast<size_t>(t[1])],
           c = m.vertices[static_cast<size_t>(t[2])];
  return 0.5 * std::imag(std::conj(b - a) * (c - a));
}

void check_mesh(const Shape& shape, const TriMesh& m, double h) {
  const double size = bounding_box(shape).diagonal();
  double total = 0, min_angle = 180;
  for (const auto& t : m.triangles) {
    const double a = tri_area(m, t);
    REQUIRE(a > 0);
    total += a;
    const cd c = (m.vertices[static_cast<size_t>(t[0])] + m.vertices[static_cast<size_t>(t[1])] +
                  m.vertices[static_cast<size_t>(t[2])]) / 3.0;
    REQUIRE(point_in_shape(shape, c));
    for (int i = 0; i < 3; ++i) {
      const cd p = m.vertices[static_cast<size_t>(t[static_cast<size_t>(i)])];
      const cd q = m.vertices[static_cast<size_t>(t[static_cast<size_t>((i + 1) % 3)])];
      const cd r = m.vertices[static_cast<size_t>(t[static_cast<size_t>((i + 2) % 3)])];
      REQUIRE(std::abs(q - p) <= h * (1 + 1e-9));
      min_angle = std::min(min_angle, std::abs(std::arg((r - p) / (q - p))) * 180 / std::numbers::pi);
    }
  }
  CHECK(total == Approx(area(shape)).epsilon(1e-9));
  // Boundary vertices lie on their loop, interior ones strictly inside.
  for (int v = 0; v < m.vertex_count(); ++v) {
    const int l = m.boundary_loop[static_cast<size_t>(v)];
    const cd p = m.vertices[static_cast<size_t>(v)];
    if (l >= 0)
      REQUIRE(loop_distance(shape.loop(l), p) < 1e-12 * size);
    else
      REQUIRE(boundary_distance(shape, p) > 1e-9 * size);
  }
  // Boundary edges: closed walks, shape on the left, total length = perimeter.
  std::vector<double> length(static_cast<size_t>(shape.loop_count()), 0.0);
  for (const auto& e : m.boundary_edges) {
    const int l = m.boundary_loop[static_cast<size_t>(e[0])];
    REQUIRE(l == m.boundary_loop[static_cast<size_t>(e[1])]);
    const cd a = m.vertices[static_cast<size_t>(e[0])], b = m.vertices[static_cast<size_t>(e[1])];
    length[static_cast<size_t>(l)] += std::abs(b - a);
    const cd left = 0.5 * (a + b) + cd(0, 1) * (b - a) * 1e-3;
    REQUIRE(point_in_shape(shape, left));
  }
  for (int l = 0; l < shape.loop_count(); ++l) CHECK(length[static_cast<size_t>(l)] == Approx(perimeter(shape.loop(l))).epsilon(1e-9));
  CHECK(min_angle > 20.0 - 1e-6);
}
}  // namespace

TEST_CASE("triangulate: generated shapes with and without holes", "[triangulate]") {
  for (const Shape& s : {test::disc(), test::annulus(), test::bar_with_holes()}) {
    const double h = bounding_box(s).diagonal() / 30;
    TriangulateOptions o;
    o.max_edge = h;
    check_mesh(s, triangulate(s, o), h);
  }
}

TEST_CASE("triangulate: every bundled shape at a vertex budget", "[triangulate][assets]") {
  for (const auto& path : test::asset_scenes()) {
    INFO(path.string());
    const Scene scene = load_scene(path);
    for (int budget : {2000, 8000}) {
      TriangulateOptions o;
      o.max_edge = edge_for_vertex_count(scene.shape, budget);
      const TriMesh m = triangulate(scene.shape, o);
      check_mesh(scene.shape, m, o.max_edge);
      // The budget (well above the outline's own vertex count) is met to within a factor of two.
      INFO("budget " << budget << ": " << m.vertex_count() << " vertices");
      CHECK(m.vertex_count() > budget / 2);
      CHECK(m.vertex_count() < budget * 2);
    }
  }
}

TEST_CASE("triangulate: refuses bad shapes and absurd sizes", "[triangulate]") {
  Shape bowtie{{{0, 0}, {1, 1}, {1, 0}, {0, 1}}, {}};
  CHECK_THROWS_AS(triangulate(bowtie), InputError);
  TriangulateOptions o;
  o.max_edge = 1e-7;
  CHECK_THROWS_WITH(triangulate(test::disc(), o), Catch::Contains("vertices (limit"));
  CHECK_THROWS_AS(edge_for_vertex_count(test::disc(), 1), InputError);
}

TEST_CASE("triangulate: triangles come in a spatially coherent (Hilbert-curve) order", "[triangulate][overlap]") {
  // The renderers draw the later triangle on top where a map overlaps itself (issue
  // #20): consecutive triangles must be neighbours in the rest shape, not scattered
  // over it as CGAL's face order leaves them, or an overlap shows a speckle of layers.
  for (const Shape& s : {normalize(Shape{test::rect(0, -0.2, 7, 0.2), {}}), test::bar_with_holes(), test::annulus()}) {
    TriangulateOptions o;
    o.max_edge = bounding_box(s).diagonal() / 100;
    const TriMesh m = triangulate(s, o);
    auto centroid = [&](size_t t) {
      const auto& tri = m.triangles[t];
      return (m.vertices[static_cast<size_t>(tri[0])] + m.vertices[static_cast<size_t>(tri[1])] +
              m.vertices[static_cast<size_t>(tri[2])]) / 3.0;
    };
    double jumps = 0;
    for (size_t t = 1; t < m.triangles.size(); ++t) jumps += std::abs(centroid(t) - centroid(t - 1));
    const double mean = jumps / static_cast<double>(m.triangles.size() - 1);
    INFO(m.triangles.size() << " triangles, mean step between consecutive centroids " << mean / o.max_edge << " max_edge");
    CHECK(mean < 1.5 * o.max_edge);
  }
}
