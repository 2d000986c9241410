// Scene editing (hsi/scene_edit.h): each rule and its refusal message, undo/redo
// restoring the exact previous scene; the inverse map of a picked point (hsi/inverse_map.h).
#include <catch2/catch.hpp>

#include "hsi/inverse_map.h"
#include "hsi/scene_edit.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

Scene bundled(const std::string& name) { return load_scene(std::string(HSI_ASSETS_DIR) + "/" + name + ".json"); }

SceneEditState state_of(const Scene& s) { return {s.handles, s.keyframes}; }

// Exact equality: an undo must give back the very same numbers.
bool same(const SceneEditState& a, const SceneEditState& b) {
  if (a.handles != b.handles || a.keyframes.size() != b.keyframes.size()) return false;
  for (size_t k = 0; k < a.keyframes.size(); ++k) {
    const Keyframe &x = a.keyframes[k], &y = b.keyframes[k];
    if (x.time != y.time || x.timing != y.timing || x.targets != y.targets || x.coefficients.has_value() != y.coefficients.has_value()) return false;
    if (x.coefficients && (x.coefficients->phi != y.coefficients->phi || x.coefficients->psi != y.coefficients->psi))
      return false;
  }
  return true;
}

EditFrame at_key(int key, int frame) { return {frame, 0.0, key, nullptr, false}; }

double max_distance(const std::vector<cd>& a, const std::vector<cd>& b) {
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

}  // namespace

TEST_CASE("an editor needs the cage and every keyframe's coefficients", "[scene_edit]") {
  Scene s = bundled("bar_holes");
  Scene no_cage = s;
  no_cage.cage.reset();
  CHECK_THROWS_WITH(SceneEditor(no_cage), Catch::Matchers::Contains("cage"));
  s.keyframes[1].coefficients.reset();
  CHECK_THROWS_WITH(SceneEditor(s), Catch::Matchers::Contains("keyframe 1 has no coefficients"));
}

TEST_CASE("adding a keyframe: refusals, appending at the last, a solved frame in time order", "[scene_edit]") {
  const Scene s = bundled("bar_holes");  // keyframes at t = 0, 1, 2
  REQUIRE(s.keyframes.size() == 3);
  SceneEditor e(s);

  SECTION("at a keyframe that is not the last: refused") {
    const EditOutcome o = e.add_keyframe(at_key(1, 30));
    CHECK_FALSE(o.done);
    CHECK_FALSE(o.error);
    CHECK(o.message == "frame 30 is keyframe 1 already: drag its handles to pose it, or add a keyframe between keyframes");
    CHECK(same(state_of(e.scene()), state_of(s)));
    CHECK_FALSE(e.can_undo());
    CHECK_FALSE(e.modified());
  }
  SECTION("at the last keyframe: a copy one time unit later") {
    const EditOutcome o = e.add_keyframe(at_key(2, 60));
    CHECK(o.done);
    CHECK(o.index == 3);
    CHECK(o.message == "added keyframe 3 at t = 3.000000");
    REQUIRE(e.scene().keyframes.size() == 4);
    const Keyframe& k = e.scene().keyframes[3];
    CHECK(k.time == s.keyframes[2].time + 1.0);
    CHECK(k.targets == s.keyframes[2].targets);
    CHECK(k.coefficients->phi == s.keyframes[2].coefficients->phi);
    CHECK(e.modified());
    CHECK(e.can_undo());
  }
  SECTION("a frame still being solved or not certified: refused, as errors") {
    EditFrame f{15, 0.5, -1, nullptr, false};
    EditOutcome o = e.add_keyframe(f);
    CHECK_FALSE(o.done);
    CHECK(o.error);
    CHECK(o.message == "frame 15 is still being solved: add the keyframe when it is shown");
    const HarmonicMap m = *s.keyframes[0].coefficients;
    f.solved = &m;
    o = e.add_keyframe(f);
    CHECK_FALSE(o.done);
    CHECK(o.error);
    CHECK(o.message == "frame 15 is not certified: it cannot become a keyframe");
    CHECK(same(state_of(e.scene()), state_of(s)));
  }
  SECTION("a certified solved frame: a keyframe at its time, targets where it sends the handles") {
    const HarmonicMap m = transform_image(*s.cage, *s.keyframes[0].coefficients, std::polar(1.0, 0.3), cd(0.1, -0.2));
    const EditOutcome o = e.add_keyframe({15, 0.5, -1, &m, true});
    CHECK(o.done);
    CHECK(o.index == 1);
    CHECK(o.message == "added keyframe 1 at t = 0.500000");
    REQUIRE(e.scene().keyframes.size() == 4);
    const Keyframe& k = e.scene().keyframes[1];
    CHECK(k.time == 0.5);
    CHECK(k.coefficients->phi == m.phi);
    CHECK(max_distance(k.targets, map_points(*s.cage, m, s.handles)) == 0);
    CHECK(e.scene().keyframes[2].time == 1.0);  // the others keep their order
  }
}

TEST_CASE("removing a keyframe: off a keyframe and the last one are refused", "[scene_edit]") {
  const Scene s = bundled("bar_holes");
  SceneEditor e(s);
  EditOutcome o = e.remove_keyframe(at_key(-1, 12));
  CHECK_FALSE(o.done);
  CHECK(o.message == "the current frame is not a keyframe: step to one (the timeline's marks) to remove it");
  o = e.remove_keyframe(at_key(1, 30));
  CHECK(o.done);
  CHECK(o.message == "removed keyframe 1");
  CHECK(e.scene().keyframes.size() == 2);
  CHECK(e.scene().keyframes[1].time == 2.0);
  CHECK(e.remove_keyframe(at_key(1, 60)).done);
  o = e.remove_keyframe(at_key(0, 0));
  CHECK_FALSE(o.done);
  CHECK(o.error);
  CHECK(o.message == "the last keyframe cannot be removed");
  CHECK(e.scene().keyframes.size() == 1);
}

TEST_CASE("adding and removing handles keeps every keyframe's pose", "[scene_edit]") {
  const Scene s = bundled("bar_holes");
  SceneEditor e(s);
  const size_t n = s.handles.size();

  EditOutcome o = e.add_handle(std::nullopt);
  CHECK_FALSE(o.done);
  CHECK(o.message == "no handle added: click on the shape");

  const cd rest(0.0, 0.45);
  o = e.add_handle(rest);
  CHECK(o.done);
  CHECK(o.index == static_cast<int>(n));
  CHECK(o.message == "added handle " + std::to_string(n) + " at rest point (0.000, 0.450)");
  REQUIRE(e.scene().handles.size() == n + 1);
  for (size_t k = 0; k < s.keyframes.size(); ++k) {
    const Keyframe& key = e.scene().keyframes[k];
    CHECK(key.coefficients->phi == s.keyframes[k].coefficients->phi);  // the pose is kept
    REQUIRE(key.targets.size() == n + 1);
    CHECK(std::abs(key.targets[n] - map_points(*s.cage, *key.coefficients, std::span<const cd>(&rest, 1))[0]) == 0);
  }

  o = e.remove_handle(static_cast<int>(n + 1));
  CHECK_FALSE(o.done);
  CHECK(o.error);
  CHECK(o.message == "no handle " + std::to_string(n + 1) + " (the scene has " + std::to_string(n + 1) + ")");
  CHECK_FALSE(e.remove_handle(-1).done);

  o = e.remove_handle(0);
  CHECK(o.done);
  CHECK(o.message == "removed handle 0");
  CHECK(e.scene().handles.size() == n);
  CHECK(e.scene().handles.front() == s.handles[1]);
  for (size_t k = 0; k < s.keyframes.size(); ++k) {
    REQUIRE(e.scene().keyframes[k].targets.size() == n);
    CHECK(e.scene().keyframes[k].targets.front() == s.keyframes[k].targets[1]);
  }
}

TEST_CASE("a pose: refusals, only certified solves kept, one undo step on commit", "[scene_edit]") {
  const Scene s = bundled("bar_holes");
  SceneEditor e(s);
  EditOutcome o = e.begin_pose(0, at_key(-1, 10));
  CHECK_FALSE(o.done);
  CHECK(o.message == "handles are posed at keyframes: pause and step to a keyframe (Page Up / Page Down), or add one here (K)");
  o = e.begin_pose(99, at_key(2, 60));
  CHECK_FALSE(o.done);
  CHECK(o.message == "no handle 99 (the scene has " + std::to_string(s.handles.size()) + ")");
  CHECK(e.pose() == nullptr);

  REQUIRE(e.begin_pose(4, at_key(2, 60)).done);
  REQUIRE(e.pose() != nullptr);
  CHECK(e.pose()->keyframe == 2);
  CHECK(max_distance(e.pose()->targets, map_points(*s.cage, *s.keyframes[2].coefficients, s.handles)) == 0);
  // While posing every other edit, undo included, is refused without a word...
  for (const EditOutcome& r : {e.add_keyframe(at_key(2, 60)), e.add_handle(cd(2, 0.1)), e.remove_handle(0), e.undo(),
                               e.redo(), e.begin_pose(3, at_key(2, 60))}) {
    CHECK_FALSE(r.done);
    CHECK(r.message.empty());
  }
  // ...but removing the keyframe, which says (as the viewer always has) to step to one.
  const EditOutcome removing = e.remove_keyframe(at_key(2, 60));
  CHECK_FALSE(removing.done);
  CHECK(removing.message == "the current frame is not a keyframe: step to one (the timeline's marks) to remove it");
  CHECK_FALSE(e.can_undo());
  CHECK(same(state_of(e.scene()), state_of(s)));

  CHECK(e.move_pose_target(cd(1.2, 0.7)));
  CHECK_FALSE(e.move_pose_target(cd(1.2, 0.7)));  // no move, no solve
  CHECK(e.pose()->targets[4] == cd(1.2, 0.7));

  KeyframeResult folding;  // an uncertified solve is never shown or kept
  folding.map = identity_map(*s.cage);
  folding.certified = false;
  folding.message = "would fold";
  e.pose_solved(folding);
  CHECK(e.pose()->latest.phi == s.keyframes[2].coefficients->phi);
  CHECK(e.pose()->status == "would fold");

  KeyframeResult good;
  good.map = transform_image(*s.cage, *s.keyframes[2].coefficients, 1.0, cd(0.01, 0));
  good.certified = true;
  good.reached = false;
  good.message = "closest certified map";
  std::vector<cd> targets = e.pose()->targets;
  o = e.commit_pose(good, targets);
  CHECK(o.done);
  CHECK(o.error);  // not reached
  CHECK(o.message == "keyframe 2: closest certified map");
  CHECK(e.pose() == nullptr);
  CHECK(e.scene().keyframes[2].coefficients->phi == good.map.phi);
  CHECK(e.scene().keyframes[2].targets == targets);

  REQUIRE(e.undo().done);  // the whole drag is one step
  CHECK(same(state_of(e.scene()), state_of(s)));

  REQUIRE(e.begin_pose(1, at_key(0, 0)).done);
  e.cancel_pose();
  CHECK(e.pose() == nullptr);
  CHECK(e.can_redo());  // a cancelled pose leaves the history alone
}

TEST_CASE("undo and redo walk back and forth through the exact scenes", "[scene_edit]") {
  const Scene s = bundled("two_holes");
  SceneEditor e(s);
  CHECK(e.undo().message == "nothing to undo");
  CHECK(e.redo().message == "nothing to redo");
  CHECK(e.undo().error);

  std::vector<SceneEditState> states = {state_of(e.scene())};
  const HarmonicMap m = transform_image(*s.cage, *s.keyframes[0].coefficients, std::polar(1.0, -0.2), cd(0.05, 0.02));
  REQUIRE(e.add_handle(s.handles[0] * 0.9 + s.handles[1] * 0.1).done);
  states.push_back(state_of(e.scene()));
  REQUIRE(e.add_keyframe({7, 0.25, -1, &m, true}).done);
  states.push_back(state_of(e.scene()));
  REQUIRE(e.remove_handle(2).done);
  states.push_back(state_of(e.scene()));
  REQUIRE(e.add_keyframe(at_key(static_cast<int>(e.scene().keyframes.size()) - 1, 99)).done);
  states.push_back(state_of(e.scene()));
  REQUIRE(e.remove_keyframe(at_key(0, 0)).done);
  states.push_back(state_of(e.scene()));

  for (size_t i = states.size() - 1; i-- > 0;) {
    const EditOutcome o = e.undo();
    CHECK(o.done);
    CHECK(o.message == "undo");
    CHECK(same(state_of(e.scene()), states[i]));
  }
  CHECK_FALSE(e.can_undo());
  for (size_t i = 1; i < states.size(); ++i) {
    const EditOutcome o = e.redo();
    CHECK(o.done);
    CHECK(o.message == "redo");
    CHECK(same(state_of(e.scene()), states[i]));
  }
  CHECK_FALSE(e.can_redo());

  // A new edit after an undo drops the redo history.
  REQUIRE(e.undo().done);
  REQUIRE(e.remove_handle(0).done);
  CHECK_FALSE(e.can_redo());
  REQUIRE(e.undo().done);
  CHECK(same(state_of(e.scene()), states[states.size() - 2]));

  e.mark_saved();
  CHECK_FALSE(e.modified());
  REQUIRE(e.undo().done);
  CHECK(e.modified());
}

TEST_CASE("a keyframe's timing: refusals, one undo step, restored by undo", "[scene_edit][timing]") {
  const Scene s = bundled("bar_holes");  // keyframes at t = 0, 1, 2
  SceneEditor e(s);
  CHECK(e.set_timing(5, KeyTiming::Smooth).message == "no keyframe 5 (the scene has 3)");
  CHECK(e.set_timing(-1, KeyTiming::Smooth).error);
  CHECK(e.set_timing(2, KeyTiming::Smooth).message == "keyframe 2 is the last: no interval leaves it, so it has no timing");
  CHECK(e.set_timing(0, KeyTiming::Linear).message == "keyframe 0 to 1 is linear already");
  CHECK_FALSE(e.can_undo());
  const EditOutcome o = e.set_timing(1, KeyTiming::Ease);
  CHECK(o.done);
  CHECK(o.message == "keyframe 1 to 2: ease timing");
  CHECK(e.scene().keyframes[1].timing == KeyTiming::Ease);
  CHECK(e.modified());
  CHECK(e.undo().done);
  CHECK(same(state_of(e.scene()), state_of(s)));
  CHECK(e.redo().done);
  CHECK(e.scene().keyframes[1].timing == KeyTiming::Ease);
}

TEST_CASE("the undo history keeps max_undo steps", "[scene_edit]") {
  const Scene s = bundled("two_holes");
  SceneEditor e(s, {.max_undo = 2});
  for (int i = 0; i < 4; ++i) REQUIRE(e.add_handle(s.handles[0] + cd(0.001 * i, 0)).done);
  CHECK(e.undo().done);
  CHECK(e.undo().done);
  CHECK_FALSE(e.undo().done);
  CHECK(e.scene().handles.size() == s.handles.size() + 2);
}

TEST_CASE("the inverse map gives back the rest point of a posed map's image point", "[scene_edit]") {
  for (const char* name : {"bar_holes", "two_holes"}) {
    const Scene s = bundled(name);
    InverseMap inverse(s.shape, *s.cage);
    const double size = bounding_box(s.shape).diagonal();
    std::vector<cd> z;  // away from the boundary, where the mesh's image covers f's
    for (const cd& p : test::interior_points(s.shape, 400))
      if (boundary_distance(s.shape, p) > 0.02 * size && z.size() < 150) z.push_back(p);
    for (size_t k = 0; k < s.keyframes.size(); ++k) {
      const HarmonicMap& map = *s.keyframes[k].coefficients;
      const std::vector<cd> w = map_points(*s.cage, map, z);
      double worst = 0;
      int missed = 0;
      for (size_t i = 0; i < z.size(); ++i) {
        const std::optional<cd> back = inverse.rest_point(map, w[i]);
        if (!back) ++missed;
        else worst = std::max(worst, std::abs(*back - z[i]));
      }
      INFO(name << " keyframe " << k << ": worst " << worst / size << " of the size, " << missed << " missed");
      CHECK(missed == 0);
      CHECK(worst <= 1e-9 * size);
    }
    // Off the image: beyond the posed shape's bounding box, and in a hole.
    const HarmonicMap& posed = *s.keyframes.back().coefficients;
    const std::vector<cd> boundary = map_points(*s.cage, posed, s.shape.outer);
    double far = 0;
    for (const cd& b : boundary) far = std::max(far, b.real());
    CHECK_FALSE(inverse.rest_point(posed, cd(far + 0.1 * size, 0)).has_value());
    const HarmonicMap id = identity_map(*s.cage);
    REQUIRE_FALSE(s.cage->hole_points.empty());
    CHECK_FALSE(inverse.rest_point(id, s.cage->hole_points[0]).has_value());
    CHECK(std::abs(*inverse.rest_point(id, z[0]) - z[0]) <= 1e-9 * size);
  }
}
