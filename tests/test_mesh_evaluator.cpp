// f at a mesh's vertices from cached basis rows (hsi/mesh_evaluator.h) against the direct
// evaluation (the basis evaluated at the points, then evaluate_map), on every bundled
// asset, with derivatives; the runtime factory's choice. The CUDA evaluator's test is in
// test_cuda_core.cpp.
#include <catch2/catch.hpp>

#include <random>

#include "hsi/mesh_evaluator.h"
#include "hsi/runtime/backend.h"
#include "hsi/scene_io.h"
#include "hsi/triangulate.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

// A map with every coefficient random (fixed seed), ψ_log = conj φ_log as in the space.
HarmonicMap random_map(const Cage& cage, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  HarmonicMap m = affine_map(cage, cd(1.2, 0.3), cd(0.1, -0.2), cd(0.5, 2));
  for (Eigen::Index j = 0; j < m.phi.size(); ++j) {
    m.phi(j) += 0.05 * cd(g(rng), g(rng));
    m.psi(j) += 0.05 * cd(g(rng), g(rng));
  }
  const int mm = cage.vertex_count();
  for (int h = 0; h < cage.hole_count(); ++h) m.psi(mm + h) = std::conj(m.phi(mm + h));
  return m;
}

double rel_gap(const VectorXcd& got, const VectorXcd& want) {
  REQUIRE(got.size() == want.size());
  if (want.size() == 0) return 0;
  return (got - want).cwiseAbs().maxCoeff() / std::max(want.cwiseAbs().maxCoeff(), 1e-300);
}

}  // namespace

TEST_CASE("f at mesh vertices from cached rows equals the direct evaluation on every asset", "[mesh_eval]") {
  for (const auto& path : test::asset_scenes()) {
    const Scene scene = load_scene(path);
    const Cage cage = scene.cage ? *scene.cage : build_cage(scene.shape, scene.cage_options);
    TriangulateOptions to;
    to.max_edge = edge_for_vertex_count(scene.shape, 1500);
    const TriMesh mesh = triangulate(scene.shape, to);
    INFO(path.filename().string() << ": " << mesh.vertex_count() << " vertices, " << basis_size(cage) << " columns");
    REQUIRE(mesh.vertex_count() % 256 != 0);  // a last, partial block of points is covered
    const auto cached = make_cpu_mesh_evaluator(cage, mesh.vertices, {.derivatives = true});
    CHECK(cached->size() == mesh.vertices.size());
    CHECK(cached->derivatives());
    CHECK(std::string(cached->name()) == "cpu");
    const BasisRows rows = evaluate_basis(cage, mesh.vertices, kBasisC | kBasisD);
    MapValues got;  // reused across maps, as a caller would per frame
    for (unsigned seed : {1u, 2u, 3u}) {
      const HarmonicMap map = random_map(cage, seed);
      const MapValues want = evaluate_map(rows, map);
      cached->evaluate(map, got);
      CHECK(rel_gap(got.f, want.f) < 1e-12);
      CHECK(rel_gap(got.f_z, want.f_z) < 1e-12);
      CHECK(rel_gap(got.fzbar_conj, want.fzbar_conj) < 1e-12);
      CHECK(got.f_zz.size() == 0);
    }
    // The identity map reproduces the points themselves (Cauchy coordinates reproduce w).
    const MapValues id = cached->evaluate(identity_map(cage));
    const VectorXcd w = Eigen::Map<const VectorXcd>(mesh.vertices.data(), mesh.vertex_count());
    CHECK(rel_gap(id.f, w) < 1e-10);
    CHECK((id.f_z.array() - 1.0).abs().maxCoeff() < 1e-9);
  }
}

TEST_CASE("the cached evaluator without derivatives, at no point, and a map of another cage", "[mesh_eval]") {
  const Shape shape = test::annulus();
  const Cage cage = build_cage(shape);
  const std::vector<cd> pts = test::interior_points(shape, 700);
  const auto e = make_cpu_mesh_evaluator(cage, pts);
  CHECK_FALSE(e->derivatives());
  const HarmonicMap map = random_map(cage, 9);
  const MapValues v = e->evaluate(map);
  CHECK(v.f_z.size() == 0);
  CHECK(v.fzbar_conj.size() == 0);
  CHECK(rel_gap(v.f, evaluate_map(cage, map, pts).f) < 1e-12);
  CHECK(mesh_evaluator_bytes(cage, pts.size()) == Approx(700.0 * basis_size(cage) * 16));

  const auto none = make_cpu_mesh_evaluator(cage, {});
  CHECK(none->evaluate(map).f.size() == 0);

  HarmonicMap wrong = map;
  wrong.phi.conservativeResize(map.phi.size() - 1);
  CHECK_THROWS_WITH(e->evaluate(wrong), Catch::Contains("the map has") && Catch::Contains("the cage needs"));
}

TEST_CASE("the CPU evaluator gives back its cached rows, in any range, and a borrowed one forwards them", "[mesh_eval]") {
  const Shape shape = test::annulus();
  const Cage cage = build_cage(shape);
  const std::vector<cd> pts = test::interior_points(shape, 3 * 128 + 45);  // blocks of 128 points, a partial last
  const BasisRows want = evaluate_basis(cage, pts, kBasisC | kBasisD);
  const auto e = make_cpu_mesh_evaluator(cage, pts, {.derivatives = true});
  const auto lent = borrow_evaluator(*e);
  MatrixXcd C, D;
  // Ranges within a block, across blocks, the last partial block, everything, none.
  for (auto [p0, n] : {std::pair<size_t, size_t>{5, 40}, {100, 200}, {384, 45}, {0, pts.size()}, {128, 0}}) {
    INFO("rows " << p0 << " + " << n);
    REQUIRE(e->rows(p0, n, C, &D));
    CHECK(C.rows() == static_cast<Eigen::Index>(n));
    CHECK(C.cols() == basis_size(cage));
    CHECK(C == want.C.middleRows(static_cast<Eigen::Index>(p0), static_cast<Eigen::Index>(n)));
    CHECK(D == want.D.middleRows(static_cast<Eigen::Index>(p0), static_cast<Eigen::Index>(n)));
    MatrixXcd C2;
    REQUIRE(lent->rows(p0, n, C2, nullptr));
    CHECK(C2 == C);
  }
  CHECK_THROWS_WITH(e->rows(400, 30, C, nullptr), Catch::Contains("asked of 429 points"));
  const auto plain = make_cpu_mesh_evaluator(cage, pts);
  CHECK(plain->rows(0, 10, C, nullptr));
  CHECK_THROWS_WITH(plain->rows(0, 10, C, &D), Catch::Contains("without derivatives"));
}

TEST_CASE("the mesh evaluator factory: cpu is the reference, auto says why it fell back", "[mesh_eval][runtime]") {
  const Shape shape = test::annulus();
  const Cage cage = build_cage(shape);
  const std::vector<cd> pts = test::interior_points(shape, 300);
  const HarmonicMap map = random_map(cage, 4);
  const VectorXcd want = evaluate_map(cage, map, pts).f;
  runtime::MeshEvaluatorChoice c = runtime::make_mesh_evaluator(cage, pts, runtime::Backend::Cpu);
  CHECK(std::string(c.evaluator->name()) == "cpu");
  CHECK(c.choice.fallback.empty());
  CHECK(rel_gap(c.evaluator->evaluate(map).f, want) < 1e-12);

  // Without a device, auto falls back to the CPU with the reason; with one, it is CUDA.
  runtime::CudaStatus none;
  none.detail = "no CUDA device (test)";
  c = runtime::make_mesh_evaluator(cage, pts, runtime::Backend::Auto, none);
  CHECK(std::string(c.evaluator->name()) == "cpu");
  CHECK(c.choice.fallback == "no CUDA device (test)");
  CHECK_THROWS_AS(runtime::make_mesh_evaluator(cage, pts, runtime::Backend::Cuda, none), runtime::BackendUnavailable);

  c = runtime::make_mesh_evaluator(cage, pts, runtime::Backend::Auto);
  CHECK(std::string(c.evaluator->name()) == (c.choice.used == runtime::Backend::Cuda ? "cuda" : "cpu"));
  CHECK(rel_gap(c.evaluator->evaluate(map).f, want) < 1e-12);
}
