// Reduced variables (math.md §3): dimension, null directions, round trips, gauges
// and full rank of the reduced basis.
#include <catch2/catch.hpp>

#include "hsi/map_space.h"
#include "hsi/samples.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

HarmonicMap random_map(const Cage& cage, unsigned seed, double amplitude = 0.1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, amplitude);
  HarmonicMap m = identity_map(cage);
  for (Eigen::Index j = 0; j < m.phi.size(); ++j) {
    m.phi(j) += cd(g(rng), g(rng));
    m.psi(j) += cd(g(rng), g(rng));
  }
  const int M = cage.vertex_count();
  for (int h = 0; h < cage.hole_count(); ++h) m.psi(M + h) = std::conj(m.phi(M + h));
  return m;
}

int expected_n(const Cage& cage) {
  int n = static_cast<int>(cage.loops[0].size()) + cage.hole_count();
  for (size_t k = 1; k < cage.loops.size(); ++k) n += static_cast<int>(cage.loops[k].size()) - 2;
  return n;
}

}  // namespace

TEST_CASE("dimensions of the reduced space", "[map_space]") {
  const Cage cage = build_cage(test::bar_with_holes());
  const MapSpace map(cage, Gauge::Map), metric(cage, Gauge::ModuloRigid);
  const int n = expected_n(cage), N = cage.hole_count();
  CHECK(map.n() == n);
  CHECK(map.dim() == 4 * n - 2 * N - 2);
  CHECK(metric.dim() == 4 * n - 2 * N - 5);
  CHECK(map.full_size() == cage.vertex_count() + N);
}

TEST_CASE("each hole loop's linear functions are null directions of the basis", "[map_space]") {
  const Shape s = test::bar_with_holes();
  const Cage cage = build_cage(s);
  const auto pts = test::interior_points(s, 200);
  const BasisRows rows = evaluate_basis(cage, pts);
  for (int k = 1; k < static_cast<int>(cage.loops.size()); ++k) {
    HarmonicMap m{VectorXcd::Zero(basis_size(cage)), VectorXcd::Zero(basis_size(cage))};
    for (size_t j = 0; j < cage.loops[static_cast<size_t>(k)].size(); ++j) {
      const cd z = cage.loops[static_cast<size_t>(k)][j];
      m.phi(cage.loop_offset(k) + static_cast<int>(j)) = cd(0.3, -2) + cd(1.5, 0.4) * z;
      m.psi(cage.loop_offset(k) + static_cast<int>(j)) = cd(-1, 1) * z;
    }
    const MapValues v = evaluate_map(rows, m);
    CHECK(v.f.cwiseAbs().maxCoeff() < 1e-11);
    CHECK(v.f_z.cwiseAbs().maxCoeff() < 1e-11);
    CHECK(v.fzbar_conj.cwiseAbs().maxCoeff() < 1e-11);
  }
}

TEST_CASE("reduce/expand round trips (map gauge keeps f exactly)", "[map_space]") {
  const Shape s = test::bar_with_holes();
  const Cage cage = build_cage(s);
  const MapSpace space(cage, Gauge::Map);
  const auto pts = test::interior_points(s, 300);
  const BasisRows rows = evaluate_basis(cage, pts);
  const HarmonicMap m = random_map(cage, 3);
  const MapSpace::Canonical c = space.reduce(m);
  REQUIRE(c.x.size() == space.dim());
  const HarmonicMap back = space.expand(c.x);
  const MapValues a = evaluate_map(rows, m), b = evaluate_map(rows, back);
  CHECK((a.f - b.f).cwiseAbs().maxCoeff() < 1e-11);
  CHECK((a.f_z - b.f_z).cwiseAbs().maxCoeff() < 1e-11);
  CHECK((a.fzbar_conj - b.fzbar_conj).cwiseAbs().maxCoeff() < 1e-11);
  // ψ_log = conj φ_log in the expanded map, dropped vertices are 0.
  for (int h = 0; h < cage.hole_count(); ++h)
    CHECK(std::abs(back.psi(cage.vertex_count() + h) - std::conj(back.phi(cage.vertex_count() + h))) < 1e-15);
  CHECK(back.psi(0) == cd(0));
  // x → map → x is the identity.
  CHECK((space.reduce(back).x - c.x).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("metric gauge: same f up to a rigid motion, same metric", "[map_space]") {
  const Shape s = test::annulus();
  const Cage cage = build_cage(s);
  const MapSpace space(cage, Gauge::ModuloRigid);
  const auto pts = test::interior_points(s, 300);
  const BasisRows rows = evaluate_basis(cage, pts);
  const HarmonicMap m = transform_image(cage, random_map(cage, 11), std::polar(1.0, 2.1), cd(5, -3));
  const MapSpace::Canonical c = space.reduce(m);
  CHECK(std::abs(std::abs(c.rotation) - 1) < 1e-14);
  const HarmonicMap canon = space.expand(c.x);
  CHECK(canon.phi(0) == cd(0));
  CHECK(std::abs(canon.phi(space.rotation_vertex()).real()) < 1e-15);
  CHECK(canon.phi(space.rotation_vertex()).imag() > 0);
  const MapValues a = evaluate_map(rows, m), b = evaluate_map(rows, canon);
  for (Eigen::Index i = 0; i < a.f.size(); ++i) {
    CHECK(std::abs(a.f(i) - (c.rotation * b.f(i) + c.translation)) < 1e-10);
    // The metric sees a·b and |a|² + |b|² only (paper Eq. 5).
    CHECK(std::abs(a.f_z(i) * a.fzbar_conj(i) - b.f_z(i) * b.fzbar_conj(i)) < 1e-10);
    CHECK(std::abs(std::norm(a.f_z(i)) - std::norm(b.f_z(i))) < 1e-10);
  }
}

TEST_CASE("reduce refuses psi_log != conj(phi_log) and wrong sizes", "[map_space]") {
  const Cage cage = build_cage(test::annulus());
  const MapSpace space(cage, Gauge::Map);
  HarmonicMap m = identity_map(cage);
  m.phi(cage.vertex_count()) = cd(0.1, 0.2);
  m.psi(cage.vertex_count()) = cd(0.1, 0.2);
  CHECK_THROWS_WITH(space.reduce(m), Catch::Matchers::Contains("conj(phi)"));
  HarmonicMap short_map{VectorXcd::Zero(3), VectorXcd::Zero(3)};
  CHECK_THROWS_WITH(space.reduce(short_map), Catch::Matchers::Contains("the cage needs"));
  CHECK_THROWS_AS(space.expand(Eigen::VectorXd::Zero(2)), InputError);
}

TEST_CASE("every asset: n, and full rank of the reduced basis in both gauges", "[map_space][assets]") {
  const auto scenes = test::asset_scenes();
  REQUIRE(!scenes.empty());
  for (const auto& path : scenes) {
    const Scene scene = load_scene(path);
    const Cage cage = scene_cage(scene);
    const MapSpace map(cage, Gauge::Map), metric(cage, Gauge::ModuloRigid);
    CHECK(map.n() == expected_n(cage));
    const BoundarySamples dense = sample_boundary(scene.shape, std::max(800, map.dim()));
    const BasisRows rows = evaluate_basis(cage, dense.points, kBasisC | kBasisD);
    const Conditioning cf = conditioning(map, rows), cm = conditioning(metric, rows);
    INFO(path.filename().string() << ": n = " << map.n() << ", sigma(f) in [" << cf.sigma_min << ", " << cf.sigma_max
                                  << "], sigma(f_z, conj f_zbar) in [" << cm.sigma_min << ", " << cm.sigma_max << "]");
    CHECK(cf.sigma_min > 1e-9 * cf.sigma_max);
    CHECK(cm.sigma_min > 1e-9 * cm.sigma_max);
    // The identity lies in the space exactly.
    const HarmonicMap id = map.expand(map.reduce(identity_map(cage)).x);
    const MapValues v = evaluate_map(rows, id);
    double err = 0;
    for (size_t i = 0; i < dense.size(); ++i) err = std::max(err, std::abs(v.f(static_cast<Eigen::Index>(i)) - dense.points[i]));
    CHECK(err < 1e-10 * bounding_box(scene.shape).diagonal());
  }
}
