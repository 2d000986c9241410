// The basis of math.md §2: derivatives against finite differences, reproduction of
// affine maps, finiteness between the shape and the cage.
#include <catch2/catch.hpp>

#include "hsi/harmonic_map.h"
#include "hsi/samples.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

// Wirtinger ∂_z and ∂_zbar of every column by central differences (step h).
void wirtinger_fd(const Cage& cage, cd w, double h, unsigned part, MatrixXcd& dz, MatrixXcd& dzbar) {
  const std::vector<cd> pts = {w + h, w - h, w + cd(0, h), w - cd(0, h)};
  const BasisRows r = evaluate_basis(cage, pts, part);
  const MatrixXcd& M = part == kBasisC ? r.C : r.D;
  const MatrixXcd dx = (M.row(0) - M.row(1)) / (2 * h), dy = (M.row(2) - M.row(3)) / (2 * h);
  dz = (dx - cd(0, 1) * dy) / 2.0;
  dzbar = (dx + cd(0, 1) * dy) / 2.0;
}

void check_derivatives(const Cage& cage, const std::vector<cd>& points, double size) {
  (void)size;
  const BasisRows rows = evaluate_basis(cage, points);
  const int m = cage.vertex_count();
  double worst_D = 0, worst_E = 0, worst_holo = 0;
  for (size_t p = 0; p < points.size(); ++p) {
    MatrixXcd dz, dzbar;
    // Step relative to the distance to the nearest singularity (cage or hole point).
    double dist = std::numeric_limits<double>::infinity();
    for (const Loop& l : cage.loops) dist = std::min(dist, loop_distance(l, points[p]));
    for (const cd& rho : cage.hole_points) dist = std::min(dist, std::abs(points[p] - rho));
    const double h = 1e-4 * dist;
    wirtinger_fd(cage, points[p], h, kBasisC, dz, dzbar);
    const auto i = static_cast<Eigen::Index>(p);
    for (int j = 0; j < basis_size(cage); ++j) {
      // Cauchy columns are holomorphic with C' = D; the real log|w − ρ| column has
      // ∂_z = 1/(2(w − ρ)) = D/2 (the pair φ log + conj(ψ log) with ψ = conj φ gives D).
      const cd expect = j < m ? rows.D(i, j) : rows.D(i, j) / 2.0;
      const double scale = std::max(1.0, std::abs(rows.D(i, j)));
      worst_D = std::max(worst_D, std::abs(dz(0, j) - expect) / scale);
      if (j < m) worst_holo = std::max(worst_holo, std::abs(dzbar(0, j)) / scale);
    }
    wirtinger_fd(cage, points[p], h, kBasisD, dz, dzbar);
    for (int j = 0; j < basis_size(cage); ++j) {
      const double scale = std::max(1.0, std::abs(rows.E(i, j))) ;
      worst_E = std::max(worst_E, std::abs(dz(0, j) - rows.E(i, j)) / scale);
      worst_holo = std::max(worst_holo, std::abs(dzbar(0, j)) / scale);
    }
  }
  INFO("max relative error: D " << worst_D << ", E " << worst_E << ", d/dzbar " << worst_holo);
  CHECK(worst_D < 1e-6);
  CHECK(worst_E < 1e-6);
  CHECK(worst_holo < 1e-6);
}

void check_affine(const Shape& shape, const Cage& cage) {
  std::vector<cd> pts = sample_boundary(shape, 400).points;
  const std::vector<cd> inner = test::interior_points(shape, 400);
  pts.insert(pts.end(), inner.begin(), inner.end());
  const BasisRows rows = evaluate_basis(cage, pts);
  for (auto [a, b, c] : {std::tuple<cd, cd, cd>{1, 0, 0}, {cd(0.7, -1.3), cd(0.2, 0.45), cd(-3, 2)}, {cd(2, 0), cd(0, -0.9), cd(0, 0)}}) {
    const MapValues v = evaluate_map(rows, affine_map(cage, a, b, c));
    const double scale = std::abs(a) + std::abs(b) + std::abs(c) + bounding_box(shape).diagonal();
    double err_f = 0, err_fz = 0, err_fzb = 0, err_fzz = 0;
    for (size_t p = 0; p < pts.size(); ++p) {
      const auto i = static_cast<Eigen::Index>(p);
      err_f = std::max(err_f, std::abs(v.f(i) - (a * pts[p] + b * std::conj(pts[p]) + c)) / scale);
      err_fz = std::max(err_fz, std::abs(v.f_z(i) - a));
      err_fzb = std::max(err_fzb, std::abs(v.fzbar_conj(i) - std::conj(b)));
      err_fzz = std::max(err_fzz, std::abs(v.f_zz(i)));
    }
    INFO("affine map a=" << a << " b=" << b << " c=" << c);
    CHECK(err_f < 1e-10);
    CHECK(err_fz < 1e-10);
    CHECK(err_fzb < 1e-10);
    CHECK(err_fzz < 1e-9);
  }
}

}  // namespace

TEST_CASE("basis derivatives match finite differences (annulus, bar)", "[basis]") {
  for (const Shape& s : {test::annulus(), test::bar_with_holes(), test::disc()}) {
    const Cage cage = build_cage(s);
    std::vector<cd> pts = sample_boundary(s, 40).points;
    const auto inner = test::interior_points(s, 20);
    pts.insert(pts.end(), inner.begin(), inner.end());
    check_derivatives(cage, pts, bounding_box(s).diagonal());
  }
}

TEST_CASE("affine maps are reproduced exactly (generated shapes)", "[basis]") {
  for (const Shape& s : {test::annulus(), test::bar_with_holes(), test::disc()}) check_affine(s, build_cage(s));
}

TEST_CASE("every asset: derivatives and affine reproduction", "[basis][assets]") {
  const auto scenes = test::asset_scenes();
  REQUIRE(!scenes.empty());
  for (const auto& path : scenes) {
    INFO("asset " << path.filename().string());
    const Scene scene = load_scene(path);
    const Cage cage = scene_cage(scene);
    const BoundarySamples g = sample_boundary(scene.shape, 30);
    std::vector<cd> pts = g.points;
    const auto inner = test::interior_points(scene.shape, 10);
    pts.insert(pts.end(), inner.begin(), inner.end());
    check_derivatives(cage, pts, bounding_box(scene.shape).diagonal());
    check_affine(scene.shape, cage);
  }
}

TEST_CASE("the basis is finite between the shape and the cage", "[basis]") {
  const Shape s = test::bar_with_holes();
  const Cage cage = build_cage(s);
  // Points between the shape's outer loop and the outer cage, and inside the holes
  // outside their cages: rejection sampling in the cage's bounding box.
  const BoundingBox bb = bounding_box(cage.loops[0]);
  std::vector<cd> pts;
  for (int i = 0; i <= 120; ++i)
    for (int j = 0; j <= 40; ++j) {
      const cd p(bb.lo.real() + (bb.hi.real() - bb.lo.real()) * i / 120.0, bb.lo.imag() + (bb.hi.imag() - bb.lo.imag()) * j / 40.0);
      if (!point_in_loop(cage.loops[0], p) || point_in_shape(s, p)) continue;
      bool in_hole_cage = false;
      for (size_t k = 1; k < cage.loops.size(); ++k) in_hole_cage |= point_in_loop(cage.loops[k], p);
      double d = loop_distance(cage.loops[0], p);
      for (size_t k = 1; k < cage.loops.size(); ++k) d = std::min(d, loop_distance(cage.loops[k], p));
      for (const cd& rho : cage.hole_points) d = std::min(d, std::abs(p - rho));
      if (!in_hole_cage && d > 1e-3) pts.push_back(p);
    }
  REQUIRE(pts.size() > 100);
  const BasisRows r = evaluate_basis(cage, pts);
  CHECK(r.C.allFinite());
  CHECK(r.D.allFinite());
  CHECK(r.E.allFinite());
  // And the identity is still reproduced there (the Cauchy formula holds in the whole cage domain).
  const MapValues v = evaluate_map(r, identity_map(cage));
  for (size_t p = 0; p < pts.size(); ++p) CHECK(std::abs(v.f(static_cast<Eigen::Index>(p)) - pts[p]) < 1e-9);
}

TEST_CASE("transform_image applies a similarity to the image", "[basis]") {
  const Shape s = test::annulus();
  const Cage cage = build_cage(s);
  const std::vector<cd> pts = test::interior_points(s, 50);
  HarmonicMap m = affine_map(cage, cd(1.1, 0.2), cd(0.1, -0.05), cd(0.3, 0));
  m.phi(cage.vertex_count()) = cd(0.05, 0.02);  // a log term too
  m.psi(cage.vertex_count()) = std::conj(m.phi(cage.vertex_count()));
  const cd r = std::polar(1.0, 0.7), t(2, -1);
  const MapValues a = evaluate_map(cage, m, pts), b = evaluate_map(cage, transform_image(cage, m, r, t), pts);
  CHECK((b.f - (r * a.f).array().matrix() - VectorXcd::Constant(a.f.size(), t)).cwiseAbs().maxCoeff() < 1e-10);
}
