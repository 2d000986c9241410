// Scene JSON: round trip and clear errors for broken files.
#include <catch2/catch.hpp>

#include <fstream>

#include "hsi/scene_io.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {
const char* kMinimal = R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[4,0],[4,2],[0,2]], "holes": [[[1,0.5],[1,1.5],[2,1.5],[2,0.5]]]}})";
Scene parse(const std::string& s) { return parse_scene(s, ".", "test.json"); }
}  // namespace

TEST_CASE("a minimal scene loads with defaults and normalized orientation", "[scene_io]") {
  const Scene s = parse(kMinimal);
  CHECK(s.shape.holes.size() == 1);
  CHECK(signed_area(s.shape.outer) > 0);
  CHECK(signed_area(s.shape.holes[0]) < 0);  // given CCW in the file, normalized to CW
  CHECK(s.samples == 10000);
  CHECK(s.hessian_ratio == 0.2);
  CHECK_FALSE(s.cage.has_value());
}

TEST_CASE("scenes round-trip through JSON, user cage and keyframes included", "[scene_io]") {
  Scene s = parse(kMinimal);
  s.name = "rt";
  s.texture = "tex.png";
  s.texture_rect = std::array<double, 4>{0, 0, 4, 2};
  s.cage = build_cage(s.shape);
  s.handles = {{0.5, 1}, {3.5, 1}};
  Keyframe k0{0.0, {{0.5, 1}, {3.5, 1}}, std::nullopt};
  Keyframe k1{1.0, {{0.5, 1}, {3.5, 2}}, identity_map(*s.cage)};
  s.keyframes = {k0, k1};
  std::filesystem::create_directories(HSI_TEST_TMP);
  const auto path = std::filesystem::path(HSI_TEST_TMP) / "roundtrip.json";
  save_scene(s, path);
  const Scene r = load_scene(path);
  CHECK(r.name == "rt");
  CHECK(r.shape.outer == s.shape.outer);
  CHECK(r.shape.holes == s.shape.holes);
  CHECK(r.texture_path() == path.parent_path() / "tex.png");
  REQUIRE(r.cage.has_value());
  CHECK(r.cage->loops == s.cage->loops);
  CHECK(r.cage->hole_points == s.cage->hole_points);
  CHECK(r.handles == s.handles);
  REQUIRE(r.keyframes.size() == 2);
  CHECK(r.keyframes[1].targets == s.keyframes[1].targets);
  REQUIRE(r.keyframes[1].coefficients.has_value());
  CHECK(r.keyframes[1].coefficients->phi == s.keyframes[1].coefficients->phi);
}

TEST_CASE("broken scene files give errors that say what and where", "[scene_io]") {
  CHECK_THROWS_WITH(parse("{\"hsi_scene\": 1,\n \"shape\": {\"outer\": [[0,0],[1,0]\n"), Contains("test.json") && Contains("invalid JSON at line 3"));
  CHECK_THROWS_WITH(parse("[1,2]"), Contains("expected a JSON object"));
  CHECK_THROWS_WITH(parse("{\"shape\": {}}"), Contains("missing \"hsi_scene\""));
  CHECK_THROWS_WITH(parse("{\"hsi_scene\": 7, \"shape\": {}}"), Contains("unsupported version 7"));
  CHECK_THROWS_WITH(parse("{\"hsi_scene\": \"1\"}"), Contains("expected an integer version"));
  CHECK_THROWS_WITH(parse("{\"hsi_scene\": 1}"), Contains("missing \"shape\""));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,"x"],[1,1]]}})"), Contains("shape.outer[1][1]: expected a number, got string"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0,3],[1,1]]}})"), Contains("shape.outer[1]: expected a point [x, y]"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]], "holes": 5}})"), Contains("shape.holes: expected an array"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,1],[1,0],[0,1]]}})"), Contains("shape: outer loop intersects itself"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "samples": 5})"), Contains("samples: expected an integer"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "handles": [[5,5]]})"), Contains("handles[0]: lies outside the shape"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "handles": [[0.5,0.2]], "keyframes": [{"time": 0, "targets": []}]})"),
                    Contains("keyframes[0].targets: has 0 targets; the scene has 1 handles"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "keyframes": [{"time": 1}, {"time": 0}]})"),
                    Contains("keyframe times must increase"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "keyframes": [{"time": 0, "phi": [[1,0]], "psi": [[0,0]]}]})"),
                    Contains("coefficients need the scene's cage"));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "cage": {"loops": [[[-1,-1],[2,-1],[2,2]]]}})"),
                    Contains("needs both \"loops\" and \"hole_points\""));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "cage": {"loops": [[[0.1,-1],[2,-1],[2,2]]], "hole_points": []}})"),
                    Contains("cage: cage loop of the outer loop touches the shape"));
  CHECK_THROWS_WITH(load_scene("/nonexistent/dir/scene.json"), Contains("/nonexistent/dir/scene.json: cannot open"));
}

TEST_CASE("keyframe coefficient vectors must match the cage", "[scene_io]") {
  Scene s = parse(kMinimal);
  s.cage = build_cage(s.shape);
  HarmonicMap bad = identity_map(*s.cage);
  bad.phi.conservativeResize(bad.phi.size() - 1);
  bad.psi.conservativeResize(bad.psi.size() - 1);
  s.keyframes = {Keyframe{0.0, {}, bad}};
  CHECK_THROWS_WITH(parse_scene(scene_to_json(s), ".", "k.json"), Contains("keyframes[0].phi: has") && Contains("the cage needs"));
}
