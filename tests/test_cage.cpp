// Automatic cages and the checks on user-given cages.
#include <catch2/catch.hpp>

#include "hsi/cage.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {
void check_automatic_cage(const Shape& s, const CageOptions& o = {}) {
  const Cage cage = build_cage(s, o);
  REQUIRE(static_cast<int>(cage.loops.size()) == s.loop_count());
  REQUIRE(cage.hole_count() == static_cast<int>(s.holes.size()));
  CHECK_NOTHROW(check_cage(s, cage));
  CHECK(signed_area(cage.loops[0]) > 0);
  for (size_t k = 0; k < cage.loops.size(); ++k) {
    CHECK(static_cast<int>(cage.loops[k].size()) <= o.max_vertices_per_loop);
    CHECK(cage.loops[k].size() >= 3);
    if (k > 0) CHECK(signed_area(cage.loops[k]) < 0);
  }
  // Far fewer vertices than the boundary when the boundary is dense.
  // Clearance: at least min_clearance × the (hole-limited) offset.
  CHECK(cage_clearance(s, cage) > 1e-3 * bounding_box(s).diagonal());
}
}  // namespace

TEST_CASE("automatic cages on generated shapes", "[cage]") {
  check_automatic_cage(test::annulus(1.0, 0.4, 400));
  check_automatic_cage(test::bar_with_holes());
  check_automatic_cage(test::disc(1.0, 500));
  CageOptions o;
  o.max_vertices_per_loop = 12;
  check_automatic_cage(test::annulus(1.0, 0.4, 400), o);
}

TEST_CASE("hole points are centres of the largest inscribed circles", "[cage]") {
  const Cage c = build_cage(test::annulus(1.0, 0.4, 400));
  CHECK(std::abs(c.hole_points[0]) < 5e-3);
  const Cage b = build_cage(test::bar_with_holes());
  for (int k = 0; k < 3; ++k) CHECK(std::abs(b.hole_points[static_cast<size_t>(k)] - cd(0.8 + 1.2 * k, 0.5)) < 5e-3);
}

TEST_CASE("automatic cages on every asset", "[cage][assets]") {
  const auto scenes = test::asset_scenes();
  REQUIRE(!scenes.empty());
  for (const auto& path : scenes) {
    INFO(path.filename().string());
    const Scene scene = load_scene(path);
    check_automatic_cage(scene.shape, scene.cage_options);
  }
}

TEST_CASE("user cages that do not fit are refused with a reason", "[cage]") {
  const Shape s = test::annulus();
  const Cage good = build_cage(s);
  REQUIRE_NOTHROW(check_cage(s, good));
  SECTION("wrong number of loops") {
    Cage c = good;
    c.loops.pop_back();
    CHECK_THROWS_WITH(check_cage(s, c), Contains("the cage has 1 loops; the shape has 2"));
  }
  SECTION("wrong number of hole points") {
    Cage c = good;
    c.hole_points.clear();
    CHECK_THROWS_WITH(check_cage(s, c), Contains("0 hole points"));
  }
  SECTION("a cage loop that is not simple") {
    Cage c = good;
    std::swap(c.loops[0][2], c.loops[0][7]);
    CHECK_THROWS_WITH(check_cage(s, c), Contains("cage loop of the outer loop is not simple"));
  }
  SECTION("a cage that cuts the shape") {
    Cage c = good;
    c.loops[0][3] *= 0.5;  // pulled inside the shape
    CHECK_THROWS_WITH(check_cage(s, c), Contains("touches the shape"));
  }
  SECTION("an outer cage that does not enclose the shape") {
    Cage c = good;
    for (cd& z : c.loops[0]) z = z * 0.05 + cd(0, 0);  // tiny, inside the hole
    c.loops[1] = test::circle(0, 0.01, 8, false);
    CHECK_THROWS(check_cage(s, c));
  }
  SECTION("a hole point outside its hole") {
    Cage c = good;
    c.hole_points[0] = {0.7, 0};
    CHECK_THROWS_WITH(check_cage(s, c), Contains("hole point 1 lies outside hole 1"));
  }
  SECTION("a cage too close to the shape") {
    Cage c = good;
    c.loops[0] = test::circle(0, 1.002, 256);  // clear of the shape, but by only 0.07% of its size
    CHECK_THROWS_WITH(check_cage(s, c), Contains("comes within"));
  }
  SECTION("non-finite cage vertex") {
    Cage c = good;
    c.loops[1][0] = {NAN, 0};
    CHECK_THROWS_WITH(check_cage(s, c), Contains("is not finite"));
  }
}

TEST_CASE("cage options are checked", "[cage]") {
  CageOptions o;
  o.clearance = -1;
  CHECK_THROWS_AS(build_cage(test::disc(), o), InputError);
  o = {};
  o.max_vertices_per_loop = 2;
  CHECK_THROWS_AS(build_cage(test::disc(), o), InputError);
}
