// Scene JSON: round trip and clear errors for broken files.
#include <catch2/catch.hpp>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

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

TEST_CASE("texture_filter: linear by default and not written; nearest round-trips; others refused", "[scene_io]") {
  Scene s = parse(kMinimal);
  CHECK(s.texture_filter == TextureFilter::Linear);
  CHECK(scene_to_json(s).find("texture_filter") == std::string::npos);  // files without it stay as they were
  s.texture_filter = TextureFilter::Nearest;
  const std::string j = scene_to_json(s);
  CHECK_THAT(j, Contains("\"texture_filter\": \"nearest\""));
  CHECK(parse(j).texture_filter == TextureFilter::Nearest);
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "texture_filter": "cubic"})"),
                    Contains("texture_filter: expected \"linear\" or \"nearest\""));
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

namespace {
// A scene with a user cage over the bar with three holes and one keyframe: a random,
// far from identity map (fixed seed), ψ_log = conj φ_log as the space needs.
Scene random_map_scene(unsigned seed) {
  Scene s;
  s.shape = test::bar_with_holes();
  s.cage = build_cage(s.shape);
  HarmonicMap m = affine_map(*s.cage, {0.8, 0.5}, {0.1, -0.2}, {3, -1});
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 0.05);
  for (Eigen::Index j = 0; j < m.phi.size(); ++j) {
    m.phi(j) += cd(n(rng), n(rng));
    m.psi(j) += cd(n(rng), n(rng));
  }
  const int vertices = s.cage->vertex_count();
  for (int h = 0; h < s.cage->hole_count(); ++h) m.psi(vertices + h) = std::conj(m.phi(vertices + h));
  s.keyframes = {Keyframe{0.0, {}, m}};
  return s;
}

nlohmann::json complex_array(const std::vector<cd>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (const cd& z : v) a.push_back({z.real(), z.imag()});
  return a;
}

// The scene's JSON with the cage given as another tool might write it: every loop in
// the other orientation (`reverse`), each loop's vertices rotated to start `shift`
// later, and the coefficients in `layout`, each following its vertex.
std::string rewritten(const Scene& s, bool reverse, int shift, const std::string& layout) {
  nlohmann::json j = nlohmann::json::parse(scene_to_json(s));
  const Cage& cage = *s.cage;
  const HarmonicMap& m = *s.keyframes[0].coefficients;
  std::vector<cd> phi, psi;
  for (int k = 0; k < static_cast<int>(cage.loops.size()); ++k) {
    const Loop& loop = cage.loops[static_cast<size_t>(k)];
    const int n = static_cast<int>(loop.size());
    std::vector<int> order;  // file position -> index in the normalized loop
    for (int i = 0; i < n; ++i) order.push_back(reverse ? ((n - 1 - i + shift) % n) : (i + shift) % n);
    std::vector<cd> verts, p, q;
    for (int i : order) {
      verts.push_back(loop[static_cast<size_t>(i)]);
      p.push_back(m.phi(cage.loop_offset(k) + i));
      q.push_back(m.psi(cage.loop_offset(k) + i));
    }
    if (layout == "reduced" && k > 0) {
      // The hole loop's Cauchy integral of a + b w vanishes outside the hole: subtract the
      // linear function through its first two (file-order) coefficients and drop them.
      for (std::vector<cd>* c : {&p, &q}) {
        const cd b = ((*c)[1] - (*c)[0]) / (verts[1] - verts[0]);
        const cd a = (*c)[0] - b * verts[0];
        for (size_t i = 0; i < verts.size(); ++i) (*c)[i] -= a + b * verts[i];
        c->erase(c->begin(), c->begin() + 2);
      }
    }
    j["cage"]["loops"][static_cast<size_t>(k)] = complex_array(verts);
    phi.insert(phi.end(), p.begin(), p.end());
    psi.insert(psi.end(), q.begin(), q.end());
  }
  for (int h = 0; h < cage.hole_count(); ++h) {
    phi.push_back(m.phi(cage.vertex_count() + h));
    psi.push_back(m.psi(cage.vertex_count() + h));
  }
  j["keyframes"][0]["phi"] = complex_array(phi);
  j["keyframes"][0]["psi"] = complex_array(psi);
  if (layout != "full") j["keyframes"][0]["layout"] = layout;
  return j.dump();
}

double max_difference(const Scene& a, const Scene& b, const std::vector<cd>& points) {
  const MapValues fa = evaluate_map(*a.cage, *a.keyframes[0].coefficients, points);
  const MapValues fb = evaluate_map(*b.cage, *b.keyframes[0].coefficients, points);
  return (fa.f - fb.f).cwiseAbs().maxCoeff();
}
}  // namespace

TEST_CASE("keyframe coefficients follow their vertices when a cage loop is given in the other orientation", "[scene_io][layout]") {
  const Scene s = random_map_scene(11);
  const double size = bounding_box(s.shape).diagonal();
  const std::vector<cd> points = test::interior_points(s.shape, 200);
  // The map is far from the identity, so a mismatch cannot hide in a small difference.
  const MapValues f = evaluate_map(*s.cage, *s.keyframes[0].coefficients, points);
  CHECK((f.f - Eigen::Map<const VectorXcd>(points.data(), static_cast<Eigen::Index>(points.size()))).cwiseAbs().maxCoeff() > 0.1 * size);
  for (const int shift : {0, 3}) {
    const Scene same = parse(rewritten(s, false, shift, "full"));
    const Scene other = parse(rewritten(s, true, shift, "full"));
    REQUIRE(other.cage.has_value());
    CHECK(signed_area(other.cage->loops[0]) > 0);
    for (size_t k = 1; k < other.cage->loops.size(); ++k) CHECK(signed_area(other.cage->loops[k]) < 0);
    CHECK(max_difference(s, same, points) <= 1e-12 * size);
    CHECK(max_difference(s, other, points) <= 1e-12 * size);
  }
}

TEST_CASE("the reduced CW17 coefficient layout gives the same map, in either orientation", "[scene_io][layout]") {
  const Scene s = random_map_scene(12);
  const double size = bounding_box(s.shape).diagonal();
  const std::vector<cd> points = test::interior_points(s.shape, 200);
  for (const bool reverse : {false, true})
    for (const int shift : {0, 5}) {
      const Scene r = parse(rewritten(s, reverse, shift, "reduced"));
      CHECK(max_difference(s, r, points) <= 1e-11 * size);
      // Saved in the full layout, it reads back as the same map.
      const Scene again = parse(scene_to_json(r));
      CHECK(max_difference(s, again, points) <= 1e-11 * size);
    }
  // The same numbers read in the full layout are a different map: the field matters.
  nlohmann::json j = nlohmann::json::parse(rewritten(s, false, 0, "reduced"));
  const int full = basis_size(*s.cage), reduced = full - 2 * s.cage->hole_count();
  j["keyframes"][0].erase("layout");
  CHECK_THROWS_WITH(parse(j.dump()), Contains("keyframes[0].phi: has " + std::to_string(reduced) + " coefficients") &&
                                         Contains("needs " + std::to_string(full) + " in the full layout") &&
                                         Contains("or " + std::to_string(reduced) + " in the reduced layout") &&
                                         Contains("add \"layout\": \"reduced\""));
  // A count that fits neither layout names both.
  j["keyframes"][0]["layout"] = "reduced";
  j["keyframes"][0]["phi"].erase(0);
  j["keyframes"][0]["psi"].erase(0);
  CHECK_THROWS_WITH(parse(j.dump()), Contains("has " + std::to_string(reduced - 1) + " coefficients in the reduced layout") &&
                                         Contains(std::to_string(full)) && Contains(std::to_string(reduced)));
  j["keyframes"][0]["layout"] = "compact";
  CHECK_THROWS_WITH(parse(j.dump()), Contains("keyframes[0].layout: expected \"full\" or \"reduced\""));
}

TEST_CASE("unknown keys are refused with their JSON path and the nearest known key", "[scene_io]") {
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "sample": 10910})"),
                    Contains("test.json: sample: unknown key; the nearest known key is \"samples\""));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "cage": {"clearence": 0.1}})"),
                    Contains("cage.clearence: unknown key; the nearest known key is \"clearance\""));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "Handles": [[0.9,0.1]]})"),
                    Contains("Handles: unknown key; the nearest known key is \"handles\""));
  CHECK_THROWS_WITH(parse(R"({"hsi_scene": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}, "keyframes": [{"time": 0, "target": []}]})"),
                    Contains("keyframes[0].target: unknown key; the nearest known key is \"targets\""));
  // A huge key is cut in the message.
  const std::string key(100000, 'k');
  try {
    parse(R"({"hsi_scene": 1, ")" + key + R"(": 1, "shape": {"outer": [[0,0],[1,0],[1,1]]}})");
    FAIL("accepted an unknown key");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Contains("unknown key") && Contains("(100000 characters)"));
    CHECK(std::string(e.what()).size() < 600);
  }
}

TEST_CASE("number errors are cut to an excerpt and given a line and column", "[scene_io]") {
  // A 100,000-digit number overflows a double: the message quotes an excerpt and says where.
  const std::string digits(100000, '7');
  try {
    parse("{\"hsi_scene\": 1,\n \"samples\": " + digits + ",\n \"shape\": {\"outer\": [[0,0],[1,0],[1,1]]}}");
    FAIL("accepted an overflowing number");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Contains("invalid JSON at line 2, column 13") && Contains("number overflow") &&
                             Contains("(100000 characters)"));
    CHECK(std::string(e.what()).size() < 600);
  }
  // 1e999 has a place too, also after the same text inside a string.
  CHECK_THROWS_WITH(parse("{\"hsi_scene\": 1, \"name\": \"1e999\",\n\n \"shape\": {\"outer\": [[0,0],[1,0],[1,1e999]]}}"),
                    Contains("invalid JSON at line 3, column 37") && Contains("1e999"));
  // A syntax error inside a long token: cut too.
  try {
    parse("{\"hsi_scene\": 1, \"shape\": " + std::string(100000, 'x') + "}");
    FAIL("accepted a bare word");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Contains("invalid JSON at line 1"));
    CHECK(std::string(e.what()).size() < 600);
  }
}
