// Global overlap (issue #20, hsi/overlap.h): the image of the boundary crossing
// itself is found (a bar rolled over itself, z² on a C-shaped ring), never reported
// for the identity or the bundled assets' keyframes, and carried through the frame
// results, frames.hsif and report.json.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "cgal_geometry.h"  // engine/src: the crossing search and its reference

#include "hsi/frames_io.h"
#include "hsi/keyframes.h"
#include "hsi/overlap.h"
#include "hsi/scene_sequence.h"
#include "random_loops.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

std::filesystem::path bent_bar_path() { return std::filesystem::path(HSI_TESTS_DIR) / "scenes" / "bent_bar.json"; }

// A C-shaped ring (270° of the annulus 1 ≤ |z| ≤ 1.5, centred at 0, away from 0).
Shape c_ring() {
  Loop l;
  const int n = 60;
  for (int k = 0; k <= n; ++k) l.push_back(std::polar(1.5, 1.5 * std::numbers::pi * k / n));
  for (int k = n; k >= 0; --k) l.push_back(std::polar(1.0, 1.5 * std::numbers::pi * k / n));
  return normalize(Shape{l, {}});
}

// φ_j = g(z_j), ψ = 0: the Cauchy-coordinate interpolant of a holomorphic g.
template <class G>
HarmonicMap holomorphic_map(const Cage& cage, G g) {
  HarmonicMap m = identity_map(cage);
  for (Eigen::Index j = 0; j < m.phi.size(); ++j) m.phi(j) = g(m.phi(j));
  return m;
}

}  // namespace

TEST_CASE("overlap: polylines that cross, touch or stay apart", "[overlap]") {
  // A simple square: nothing.
  CHECK(polyline_overlap({test::rect(0, 0, 1, 1)}).crossings == 0);
  CHECK(polyline_overlap({test::rect(0, 0, 1, 1)}).checked);
  // A bow tie: its edges 1 and 3 cross once at (0.5, 0.5).
  const OverlapResult bow = polyline_overlap({{{0, 0}, {1, 1}, {1, 0}, {0, 1}}});
  CHECK(bow.crossings == 1);
  CHECK(bow.loop_a == 0);
  CHECK(bow.loop_b == 0);
  CHECK(bow.edge_a == 0);
  CHECK(bow.edge_b == 2);
  CHECK(std::abs(bow.point - cd(0.5, 0.5)) < 1e-12);
  // Two loops: a hole poking out of the outer loop crosses it twice.
  const OverlapResult two = polyline_overlap({test::rect(0, 0, 4, 4), test::rect(3, 1, 5, 2)});
  CHECK(two.crossings == 2);
  CHECK(two.loop_a == 0);
  CHECK(two.loop_b == 1);
  // Disjoint loops, and repeated points (zero-length segments) do not count.
  CHECK(polyline_overlap({test::rect(0, 0, 1, 1), test::rect(2, 2, 3, 3)}).crossings == 0);
  CHECK(polyline_overlap({{{0, 0}, {1, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}}}).crossings == 0);
  CHECK_THAT(describe(bow), Catch::Matchers::Contains("overlaps itself"));
}

TEST_CASE("overlap: identity none, z^2 on a C-shaped ring double-covers", "[overlap]") {
  const Shape shape = c_ring();
  const ShapeSetup setup(shape, build_cage(shape), 2000, 0.2);
  const OverlapResult id = setup.overlap.check(identity_map(setup.cage));
  CHECK(id.checked);
  CHECK(id.crossings == 0);
  CHECK(id.points == setup.certifier.breakpoint_count());
  // z ↦ z² doubles the angles: 270° become 540°, the ring's ends overlap its middle.
  const HarmonicMap sq = holomorphic_map(setup.cage, [](cd z) { return z * z; });
  REQUIRE(setup.certifier.certify(sq).certified);  // locally injective (f_z ≈ 2z ≠ 0, f_zbar = 0)
  const OverlapResult r = setup.overlap.check(sq);
  INFO(describe(r));
  CHECK(r.overlaps());
  CHECK(r.crossings >= 2);
  CHECK(r.loop_a == 0);
  // The crossing point is in the image (radius between 1 and 2.25).
  CHECK(std::abs(r.point) > 0.9);
  CHECK(std::abs(r.point) < 2.4);
  // A rigid motion of the image changes nothing.
  const OverlapResult moved = setup.overlap.check(transform_image(setup.cage, sq, std::polar(1.0, 0.7), cd(3, -2)));
  CHECK(moved.crossings == r.crossings);
}

TEST_CASE("overlap: the bent bar's keyframe overlaps itself, is certified, and frames carry it", "[overlap]") {
  Scene scene = load_scene(bent_bar_path());
  SceneSequenceOptions o;
  o.frames = 3;
  const auto setup = scene_setup(scene);
  const OverlapResult k0 = setup->overlap.check(*scene.keyframes[0].coefficients);
  const OverlapResult k1 = setup->overlap.check(*scene.keyframes[1].coefficients);
  INFO(describe(k1));
  CHECK(k0.crossings == 0);
  CHECK(k1.overlaps());
  CHECK(k1.loop_a == 0);
  REQUIRE(setup->certifier.certify(*scene.keyframes[1].coefficients).certified);

  SceneSequence seq = interpolate_scene(scene, o, {}, nullptr, setup);
  REQUIRE(seq.frames.size() == 3);
  CHECK(seq.frames[0].overlap.checked);
  CHECK_FALSE(seq.frames[0].overlap.overlaps());
  CHECK(seq.frames[1].overlap.checked);  // a solved frame is checked too
  CHECK(seq.frames[2].keyframe);
  CHECK(seq.frames[2].overlap.overlaps());
  CHECK(seq.frames[2].overlap.crossings == k1.crossings);
  CHECK(summarize(seq.frames, 0).overlapping == (seq.frames[1].overlap.overlaps() ? 2 : 1));

  // frames.hsif: flag 8, and back.
  const FrameFile back = decode_frames(encode_frames(seq.frame_file()));
  REQUIRE(back.frames.size() == 3);
  for (size_t i = 0; i < 3; ++i) CHECK(back.frames[i].overlaps == seq.frames[i].overlap.overlaps());
  CHECK(back.frames[2].overlaps);
  // report.json: per frame and in the summary.
  const nlohmann::json rep = nlohmann::json::parse(report_json(scene, seq));
  CHECK(rep["frames"][2]["overlaps"] == true);
  CHECK(rep["frames"][2]["overlap"]["crossings"] == k1.crossings);
  CHECK(rep["frames"][2]["overlap"]["first"]["loop_a"] == 0);
  CHECK(rep["frames"][0]["overlaps"] == false);
  CHECK(rep["summary"]["overlapping"] == summarize(seq.frames, 0).overlapping);
  // report CSV: the overlap columns, after the sampled bound_excess.
  const std::string csv = report_csv(seq);
  CHECK(csv.find(",bound_excess,overlaps,crossings,certified_sigma1_max,") != std::string::npos);
  CHECK(csv.find(",1," + std::to_string(k1.crossings) + ",") != std::string::npos);
}

TEST_CASE("overlap: frames.hsif refuses flags above 15, keeps 8", "[overlap]") {
  FrameFile f;
  f.cage = build_cage(test::disc());
  f.frames.push_back({0.0, true, true, true, 0, 2.0, identity_map(f.cage)});
  f.frames.back().overlaps = true;
  std::string bytes = encode_frames(f);
  CHECK(decode_frames(bytes).frames[0].overlaps);
  // The flags word of frame 0 follows its time (8 bytes) at the end minus the record.
  const size_t K = static_cast<size_t>(basis_size(f.cage));
  const size_t at = bytes.size() - (24 + 32 * K) + 8;
  CHECK(static_cast<unsigned char>(bytes[at]) == (1u | 2u | 4u | 8u));
  bytes[at] = static_cast<char>(16);
  CHECK_THROWS_WITH(decode_frames(bytes), Catch::Matchers::Contains("unknown frame flags 16"));
}

TEST_CASE("overlap: no bundled asset's keyframe overlaps itself", "[overlap][assets]") {
  for (const auto& path : test::asset_scenes()) {
    Scene scene = load_scene(path);
    const auto setup = scene_setup(scene);
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      REQUIRE(scene.keyframes[k].coefficients);
      const OverlapResult r = setup->overlap.check(*scene.keyframes[k].coefficients);
      INFO(path.filename().string() << " keyframe " << k << ": " << describe(r));
      CHECK(r.checked);
      CHECK(r.crossings == 0);
    }
  }
}

TEST_CASE("overlap: a round-off fold-back a hair's width from a vertex is not a crossing; a real one is", "[overlap]") {
  // A square whose corner at (1, 0) carries an extra point 1e-12 past the corner and
  // back (the image of a sample next to a vertex, shifted by round-off): with exact
  // predicates alone its two neighbours "cross" at the corner.
  const Loop square = {{0, 0}, {1, 0}, {1 + 1e-12, -1e-12}, {1 - 1e-13, 1e-13}, {1, 1}, {0, 1}};
  CHECK_FALSE(polyline_overlap({square}).overlaps());
  // A bow tie still crosses, and so does a fold of 1e-6 of the size (visible at 1e6 px).
  CHECK(polyline_overlap({{{0, 0}, {1, 1}, {1, 0}, {0, 1}}}).overlaps());
  const Loop folded = {{0, 0}, {1, 0}, {1 + 1e-6, -1e-6}, {1 - 1e-6, 1e-6}, {1, 1}, {0, 1}};
  CHECK(polyline_overlap({folded}).overlaps());
}

namespace {


std::vector<std::pair<std::array<int, 2>, std::array<int, 2>>> pairs_of(
    const std::vector<std::pair<detail::EdgeRef, detail::EdgeRef>>& found) {
  std::vector<std::pair<std::array<int, 2>, std::array<int, 2>>> out;
  for (const auto& [a, b] : found) out.push_back({{a.loop, a.edge}, {b.loop, b.edge}});
  return out;
}

}  // namespace

TEST_CASE("overlap: the box hierarchy finds exactly the pairs CGAL's box sweep found, on large random polylines",
          "[overlap]") {
  std::mt19937 rng(2023);
  for (int kind = 0; kind < 3; ++kind)
    for (int points : {30, 3000, 12000}) {
      // Kinds 0-2: noisy circles (simple), random walks (many crossings), integer-grid walks (collinear overlaps, touchings).
      const std::vector<Loop> loops = hsi::test::random_loops(rng, kind, points);
      std::vector<const Loop*> ptrs;
      for (const Loop& l : loops) ptrs.push_back(&l);
      const auto want = detail::intersecting_edges_box_sweep(ptrs, std::numeric_limits<size_t>::max());
      const auto got = detail::intersecting_edges(ptrs, std::numeric_limits<size_t>::max());
      INFO("kind " << kind << ", " << points << " points: " << want.size() << " pairs");
      if (kind == 0) CHECK(want.empty());  // noisy circles apart stay simple
      if (kind > 0 && points > 1000) CHECK(want.size() > 100);
      CHECK(pairs_of(got) == pairs_of(want));
      // Truncated: the pairs found are real ones, as many as asked for.
      const auto few = detail::intersecting_edges(ptrs, 5);
      CHECK(few.size() == std::min<size_t>(5, want.size()));
      for (const auto& p : pairs_of(few)) CHECK(std::find(pairs_of(want).begin(), pairs_of(want).end(), p) != pairs_of(want).end());
    }
}

TEST_CASE("overlap: the image from cached rows is the dense product's to round-off, with the same verdicts", "[overlap]") {
  Scene bent = load_scene(bent_bar_path());
  std::vector<std::pair<Scene, std::string>> scenes{{bent, "bent_bar"}};
  for (const char* name : {"bar_holes.json", "glyph_B.json"})
    scenes.push_back({load_scene(std::filesystem::path(HSI_ASSETS_DIR) / name), name});
  for (auto& [scene, name] : scenes) {
    const auto setup = scene_setup(scene);
    const CertificateSegments& bp = setup->overlap.breakpoints();
    const MatrixXcd C = evaluate_basis(setup->cage, bp.points, kBasisC).C;
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      const HarmonicMap& map = *scene.keyframes[k].coefficients;
      const VectorXcd dense = C * map.phi + (C * map.psi).conjugate();  // what the checker computed before issue #23
      const VectorXcd cached = setup->overlap.image(map);
      INFO(name << " keyframe " << k);
      REQUIRE(cached.size() == dense.size());
      CHECK((cached - dense).cwiseAbs().maxCoeff() <= 1e-12 * setup->size);
      const OverlapResult a = setup->overlap.check(map);
      const OverlapResult b = setup->overlap.check_points(std::span<const cd>(dense.data(), static_cast<size_t>(dense.size())));
      CHECK(a.crossings == b.crossings);
      CHECK(a.points == b.points);
      CHECK(a.loop_a == b.loop_a);
      CHECK(a.edge_a == b.edge_a);
      CHECK(a.loop_b == b.loop_b);
      CHECK(a.edge_b == b.edge_b);
    }
  }
}
