// Keyframe authoring by handles (math.md §7) and import of coefficient keyframes.
#include <catch2/catch.hpp>

#include <filesystem>

#include "hsi/keyframes.h"
#include "hsi/scene_io.h"
#include "hsi/shape_setup.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {
std::unique_ptr<ShapeSetup> setup_for(const Shape& s, int samples = 2000) {
  return std::make_unique<ShapeSetup>(s, build_cage(s), samples, 0.2);
}
}  // namespace

TEST_CASE("a rigid pose is reached exactly and reproduces the rigid map", "[keyframes]") {
  const auto setup = setup_for(test::annulus());
  const std::vector<cd> handles = {{0.7, 0}, {-0.35, 0.6}, {-0.35, -0.6}};
  const cd r = std::polar(1.0, 0.5), t(0.3, -0.2);
  std::vector<cd> targets;
  for (const cd& h : handles) targets.push_back(r * h + t);
  const KeyframeResult k = author_keyframe(*setup, handles, targets, identity_map(setup->cage));
  INFO(k.message);
  CHECK(k.certified);
  CHECK(k.reached);
  CHECK(k.energy == Approx(2.0).epsilon(1e-6));
  const auto pts = test::interior_points(setup->shape, 200);
  const std::vector<cd> f = map_points(setup->cage, k.map, pts);
  for (size_t i = 0; i < pts.size(); ++i) CHECK(std::abs(f[i] - (r * pts[i] + t)) < 1e-4);
}

TEST_CASE("a large bend of a bar with holes is reached and certified", "[keyframes]") {
  const auto setup = setup_for(test::bar_with_holes());
  const std::vector<cd> handles = {{0.2, 0.5}, {1.4, 0.5}, {2.6, 0.5}, {3.8, 0.5}};
  // Bend the centre line y = 0.5 onto a quarter circle (90°).
  const double R = 3.6 / (std::numbers::pi / 2);
  std::vector<cd> targets;
  for (const cd& h : handles) {
    const double a = (h.real() - 2.0) / R;
    targets.push_back(cd(2.0 + R * std::sin(a), 0.5 + R * (1 - std::cos(a))));
  }
  int last_stage = 0;
  const KeyframeResult k = author_keyframe(*setup, handles, targets, identity_map(setup->cage), {},
                                           [&](int stage, int) { last_stage = stage; });
  INFO(k.message << ", " << k.iterations << " iterations");
  CHECK(k.certified);
  CHECK(k.reached);
  CHECK(k.max_target_error < 1e-3);
  CHECK(last_stage == KeyframeOptions{}.stages);
  CHECK(k.certificate.certified);
  CHECK(k.energy > 2.0);
}

TEST_CASE("targets no map can reach end at the closest certified map, with a message", "[keyframes]") {
  // Two handles 1e-3 apart sent 3 units apart: the singular values inside are bounded
  // by those on the boundary (Theorem 2), so this needs a stretch of 3000 on ∂Ω, far
  // more distortion than the positional term can pay; the solver must stop at a
  // certified map and say the targets were not reached.
  const auto setup = setup_for(test::bar_with_holes());
  const std::vector<cd> handles = {{1.4, 0.5}, {1.401, 0.5}, {0.2, 0.5}};
  const std::vector<cd> targets = {{0.5, 0.5}, {3.5, 0.5}, {0.2, 0.5}};
  KeyframeOptions o;  // a short solve: the verdict is what matters here
  o.stages = 2;
  o.stage_iterations = 5;
  o.newton.max_iterations = 10;
  const KeyframeResult k = author_keyframe(*setup, handles, targets, identity_map(setup->cage), o);
  CHECK(k.certified);
  CHECK_FALSE(k.reached);
  CHECK_THAT(k.message, Contains("not reached") && Contains("closest certified map"));
  CHECK(setup->certifier.certify(k.map).certified);
  // Short of the fold by a margin (KeyframeOptions' NewtonOptions::min_margin), so that
  // its coefficients in the interpolation's reduced space are certified too.
  CHECK(k.certificate.min_margin >= 1e-6 * k.certificate.sigma1_max);
  CHECK(setup->certifier.certify(setup->metric_space.expand(setup->metric_space.reduce(k.map).x)).certified);
}

TEST_CASE("imported keyframes are certified; folding or malformed ones are refused", "[keyframes]") {
  const auto setup = setup_for(test::annulus(), 1000);
  CHECK_NOTHROW(import_keyframe(*setup, affine_map(setup->cage, cd(1.2, 0.3), 0.2, 1.0)));
  CHECK_THROWS_WITH(import_keyframe(*setup, affine_map(setup->cage, 1.0, 1.3, 0.0), "keyframe 1"),
                    Contains("keyframe 1 is not locally injective"));
  HarmonicMap bad = identity_map(setup->cage);
  bad.phi.conservativeResize(3);
  CHECK_THROWS_WITH(import_keyframe(*setup, bad), Contains("the cage needs"));
  HarmonicMap nan_map = identity_map(setup->cage);
  nan_map.psi(2) = cd(NAN, 0);
  CHECK_THROWS_WITH(import_keyframe(*setup, nan_map), Contains("not finite"));
  CHECK_THROWS_AS(author_keyframe(*setup, std::vector<cd>{{0.7, 0}}, std::vector<cd>{}, identity_map(setup->cage)), InputError);
  // A handle in a hole (where the basis is singular at the hole point) is refused.
  CHECK_THROWS_WITH(author_keyframe(*setup, std::vector<cd>{{0.0, 0.0}}, std::vector<cd>{{1, 1}}, identity_map(setup->cage)),
                    Contains("handle 0") && Contains("lies outside the shape, in hole 1, 0.399"));
}

TEST_CASE("every bundled scene has at least two keyframes, all certified", "[keyframes][assets]") {
  const auto scenes = test::asset_scenes();
  REQUIRE(!scenes.empty());
  for (const auto& path : scenes) {
    INFO(path.filename().string());
    Scene scene = load_scene(path);
    CHECK(scene.keyframes.size() >= 2);
    REQUIRE(scene.cage.has_value());  // coefficients are stored over the scene's own cage
    const auto setup = make_shape_setup(scene);
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      INFO("keyframe " << k);
      REQUIRE(scene.keyframes[k].coefficients.has_value());
      CHECK_NOTHROW(import_keyframe(*setup, *scene.keyframes[k].coefficients));
      // The stored pose still puts the handles on their targets.
      if (!scene.keyframes[k].targets.empty()) {
        const std::vector<cd> got = map_points(setup->cage, *scene.keyframes[k].coefficients, scene.handles);
        for (size_t h = 0; h < got.size(); ++h) CHECK(std::abs(got[h] - scene.keyframes[k].targets[h]) < 1e-3 * setup->size);
      }
    }
  }
}

// Keyframe::start (scene "start": "rest"): authoring from targets starts at the rest pose
// instead of the previous keyframe. On two_holes, keyframe 0 turns the whole shape by
// 2.5 rad (and scales it 1.3), keyframe 1 turns its right-hand part 2 rad from rest and
// keyframe 2 is the rest pose moved: authored each from the one before, keyframe 2 meets
// its targets but stays twisted over itself (energy ~42, 14 crossings; found by a
// generated scene, 2026-12-05); from rest it is the rigid motion itself.
TEST_CASE("a keyframe authored from rest depends on its targets alone", "[keyframes][long]") {
  Scene scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json");
  const std::vector<cd> rest = scene.handles;
  REQUIRE(rest.size() == 7);
  const cd spin = 1.3 * std::polar(1.0, 2.5), turn = std::polar(1.0, 2.0), about = rest[3], shift(0.5, -0.3);
  std::vector<cd> k0, k1, k2;
  for (size_t i = 0; i < rest.size(); ++i) {
    k0.push_back(spin * rest[i]);
    k1.push_back(i < 3 ? rest[i] : about + turn * (rest[i] - about));
    k2.push_back(rest[i] + shift);
  }
  scene.keyframes = {Keyframe{0, k0, {}}, Keyframe{1, k1, {}}, Keyframe{2, k2, {}}};
  scene.samples = 2000;
  const auto setup = make_shape_setup(scene, 2000, 0.2);
  scene.cage = setup->cage;
  const std::vector<SceneKeyframe> a = solve_scene_keyframes(scene, *setup);
  REQUIRE(a.size() == 3);
  CHECK_FALSE(a[2].from_rest);
  // Keyframes 0 and 1 as solved; keyframe 2 again, from rest.
  Scene from_rest = scene;
  from_rest.keyframes[2].coefficients.reset();
  from_rest.keyframes[2].start = Keyframe::Start::Rest;
  const std::vector<SceneKeyframe> b = solve_scene_keyframes(from_rest, *setup);
  REQUIRE(b.size() == 3);
  CHECK_FALSE(b[1].solved);  // given as coefficients now: only certified
  CHECK(b[2].from_rest);
  REQUIRE(b[2].result.certified);
  CHECK(b[2].result.reached);
  CHECK(b[2].result.energy == Approx(2.0).epsilon(1e-6));  // the isometry
  CHECK_FALSE(b[2].overlap.overlaps());
  const auto pts = test::interior_points(setup->shape, 100);
  const std::vector<cd> f = map_points(setup->cage, *from_rest.keyframes[2].coefficients, pts);
  for (size_t i = 0; i < pts.size(); ++i) CHECK(std::abs(f[i] - (pts[i] + shift)) < 1e-4 * setup->size);
  // From keyframe 1 the same targets are met by a map folded over itself.
  INFO("from keyframe 1: energy " << a[2].result.energy);
  CHECK(a[2].result.reached);
  CHECK(a[2].overlap.overlaps());
  CHECK(a[2].result.energy > 10);
}
