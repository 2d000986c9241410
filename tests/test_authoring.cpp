// Scene authoring (issue #22): handles and keyframes added by the library's rules,
// frame times that hit every keyframe.
#include <catch2/catch.hpp>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

TEST_CASE("frame_times: every keyframe time is a frame time, exactly", "[authoring]") {
  const std::vector<double> keys{0.0, 0.3, 1.7, 2.0};  // uneven intervals
  const std::vector<double> t = frame_times(keys, 5);
  REQUIRE(t.size() == 3 * 5 + 1);
  for (size_t k = 0; k < keys.size(); ++k) CHECK(t[5 * k] == keys[k]);  // bitwise: Interpolator::frame compares with ==
  for (size_t i = 1; i < t.size(); ++i) CHECK(t[i] > t[i - 1]);
  CHECK(t[1] == Approx(0.06));
  CHECK(t[6] == Approx(0.58));
  CHECK(frame_times({0.0, 2.0}, 1) == std::vector<double>{0.0, 2.0});
  // The README's example: [0, 2] with three keyframes, 500 uniform frames miss t = 1.
  const std::vector<double> readme{0.0, 1.0, 2.0};
  bool hit = false;
  for (int i = 0; i < 500; ++i) hit = hit || 0.0 + 2.0 * i / 499 == 1.0;
  CHECK_FALSE(hit);
  CHECK(frame_times(readme, 250)[250] == 1.0);
  CHECK_THROWS_WITH(frame_times(readme, 0), Contains("at least 1"));
  CHECK_THROWS_WITH(frame_times({1.0}, 3), Contains("at least two keyframes"));
}

TEST_CASE("a sequence at frame_times reproduces every keyframe as a frame", "[authoring]") {
  const Shape s = test::annulus(1.0, 0.45, 96);
  const ShapeSetup setup(s, build_cage(s), 600, 0.2);
  const std::vector<double> keys{0.0, 0.5, 2.0};
  const std::vector<HarmonicMap> maps{identity_map(setup.cage), affine_map(setup.cage, {1.1, 0.2}, {0.05, 0}, {0.3, 0}),
                                      affine_map(setup.cage, {0.9, -0.3}, {0, 0.04}, {-0.2, 0.4})};
  Interpolator interp(setup, keys, maps);
  const std::vector<FrameResult> frames = interp.sequence(frame_times(keys, 2));
  REQUIRE(frames.size() == 5);
  for (int i : {0, 2, 4}) {
    CHECK(frames[static_cast<size_t>(i)].keyframe);
    CHECK(frames[static_cast<size_t>(i)].map.phi == maps[static_cast<size_t>(i / 2)].phi);
  }
  CHECK_FALSE(frames[1].keyframe);
  CHECK(frames[1].certified);
  CHECK_THROWS_WITH(interp.sequence(std::vector<double>{0.0, 3.0}), Contains("frame times must increase within"));
}

TEST_CASE("add_handle and add_keyframe keep poses and refuse what cannot work", "[authoring]") {
  Scene scene;
  scene.shape = test::bar_with_holes();
  scene.source = "bar.json";
  // No handles yet: a keyframe has nothing to pose.
  CHECK_THROWS_WITH(add_keyframe(scene, 0, {}), Contains("the scene has no handles; add handles first"));
  CHECK_THROWS_WITH(add_handle(scene, {0.8, 0.5}), Contains("handle 0 at (0.8, 0.5): lies outside the shape, in hole 1, "));
  // How far outside: (9, 9) is 8 above the bar's top right corner (4, 1): sqrt(25 + 64).
  CHECK_THROWS_WITH(add_handle(scene, {9, 9}), Contains("beyond the outer loop, 9.434 from the shape") && Contains("bounding box"));
  add_handle(scene, {0.2, 0.5});
  add_handle(scene, {3.8, 0.5});
  CHECK(add_keyframe(scene, 1.0, {{0.2, 0.5}, {3.9, 1.0}}) == 0);
  CHECK(add_keyframe(scene, 0.0, {}) == 0);  // inserted in time order, the rest pose
  CHECK(scene.keyframes[0].targets == scene.handles);
  CHECK_THROWS_WITH(add_keyframe(scene, 1.0, {}), Contains("keyframe 1 is at that time already"));
  CHECK_THROWS_WITH(add_keyframe(scene, 2.0, {{1, 1}}), Contains("has 1 targets; the scene has 2 handles"));
  // Keyframes given by targets only: a new handle's target there is unknown.
  CHECK_THROWS_WITH(add_handle(scene, {2.0, 0.1}), Contains("keyframe 0 is given by targets only"));
  // Once solved, a new handle's targets are its images: every keyframe keeps its pose.
  auto setup = scene_setup(scene, 1000);
  // The solver checks a handle's place before solving, with the same words (one check).
  const std::vector<cd> in_hole{{0.8, 0.5}};
  CHECK_THROWS_WITH(author_keyframe(*setup, in_hole, in_hole, identity_map(setup->cage)),
                    Contains("handle 0 at (0.8, 0.5) lies outside the shape, in hole 1, 0.24") && Contains("% of its size)"));
  // Small settings (two drag stages, few iterations): the poses only need to be certified
  // maps; what is proved is that a new handle's targets are its images under them.
  KeyframeOptions quick;
  quick.stages = 2;
  quick.stage_iterations = 10;
  quick.newton.max_iterations = 40;
  solve_scene_keyframes(scene, *setup, quick);
  const std::vector<HarmonicMap> before{*scene.keyframes[0].coefficients, *scene.keyframes[1].coefficients};
  add_handle(scene, {2.0, 0.1});
  REQUIRE(scene.handles.size() == 3);
  for (size_t k = 0; k < 2; ++k) {
    REQUIRE(scene.keyframes[k].targets.size() == 3);
    const cd image = map_points(*scene.cage, before[k], std::vector<cd>{{2.0, 0.1}})[0];
    CHECK(std::abs(scene.keyframes[k].targets[2] - image) < 1e-12);
  }
  // Solving again from the new targets reproduces the poses (they are reachable: they are the poses).
  for (Keyframe& k : scene.keyframes) k.coefficients.reset();
  for (const SceneKeyframe& k : solve_scene_keyframes(scene, *setup, quick)) CHECK(k.result.reached);
}
