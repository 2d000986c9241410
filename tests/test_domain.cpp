// Shapes: orientation, geometry helpers, and every refusal of validate().
#include <catch2/catch.hpp>

#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

TEST_CASE("normalize orients the outer loop CCW and holes CW", "[domain]") {
  Shape s{test::circle(0, 1, 32, false), {test::circle(0, 0.3, 16, true)}};
  s = normalize(s);
  CHECK(signed_area(s.outer) > 0);
  CHECK(signed_area(s.holes[0]) < 0);
  CHECK(area(s) == Approx(std::numbers::pi * (1 - 0.09)).epsilon(0.02));
}

TEST_CASE("valid shapes pass validation", "[domain]") {
  CHECK_NOTHROW(validate(test::annulus()));
  CHECK_NOTHROW(validate(test::bar_with_holes()));
  CHECK_NOTHROW(validate(test::disc()));
}

TEST_CASE("validation refuses each kind of bad shape and says where", "[domain]") {
  SECTION("fewer than 3 vertices") {
    Shape s{{{0, 0}, {1, 0}}, {}};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop has 2 vertices"));
  }
  SECTION("hole with fewer than 3 vertices") {
    Shape s = test::annulus();
    s.holes[0].resize(2);
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 has 2 vertices"));
  }
  SECTION("NaN coordinate") {
    Shape s = test::disc();
    s.outer[5] = {std::nan(""), 0};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop vertex 5") && Contains("non-finite"));
  }
  SECTION("infinite coordinate in a hole") {
    Shape s = test::annulus();
    s.holes[0][3] = {0, INFINITY};
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 vertex 3") && Contains("non-finite"));
  }
  SECTION("duplicate consecutive vertex (zero-length edge)") {
    Shape s = test::disc();
    s.outer.insert(s.outer.begin() + 10, s.outer[10]);
    CHECK_THROWS_WITH(validate(s), Contains("zero-length outer loop edge 10"));
  }
  SECTION("degenerate area") {
    Shape s{{{0, 0}, {1, 0}, {0.5, 1e-12}}, {}};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop encloses (almost) no area"));
    Shape line{{{0, 0}, {1, 0}, {2, 0}}, {}};  // collinear: its edges overlap
    CHECK_THROWS_WITH(validate(line), Contains("outer loop intersects itself"));
  }
  SECTION("self-intersection (bow tie)") {
    Shape s{{{0, 0}, {1, 1}, {1, 0}, {0, 1}}, {}};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop intersects itself") && Contains("edge 0") && Contains("edge 2"));
  }
  SECTION("self-intersection in a hole") {
    Shape s{test::rect(-2, -2, 2, 2), {{{-1, -1}, {1, 1}, {1, -1}, {-1, 1}}}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 intersects itself"));
  }
  SECTION("a spike folding back onto itself") {
    Shape s{{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 3}, {1, 2}, {0, 1}}, {}};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop intersects itself"));
  }
  SECTION("a hole crossing the outer loop") {
    Shape s{test::rect(0, 0, 2, 2), {test::circle({2, 1}, 0.5, 16, false)}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 crosses the outer loop"));
  }
  SECTION("two holes crossing each other") {
    Shape s{test::rect(0, 0, 4, 2), {test::circle({1.5, 1}, 0.6, 16, false), test::circle({2.2, 1}, 0.6, 16, false)}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 2 crosses the hole 1"));
  }
  SECTION("a hole outside the outer loop") {
    Shape s{test::rect(0, 0, 2, 2), {test::circle({5, 5}, 0.5, 16, false)}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 lies outside the outer loop"));
  }
  SECTION("a hole inside another hole") {
    Shape s{test::rect(0, 0, 4, 4), {test::circle({2, 2}, 1.5, 32, false), test::circle({2, 2}, 0.5, 16, false)}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 2 lies inside hole 1"));
  }
  SECTION("a hole touching the outer loop at a vertex") {
    Shape s{test::rect(0, 0, 2, 2), {{{0, 1}, {1, 0.5}, {1, 1.5}}}};
    CHECK_THROWS_WITH(validate(s), Contains("hole 1 crosses the outer loop"));
  }
  SECTION("a repeated (non-consecutive) vertex pinches the loop") {
    Shape s{{{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 1}}, {}};
    CHECK_THROWS_WITH(validate(s), Contains("outer loop intersects itself"));
  }
}

TEST_CASE("geometry helpers", "[domain]") {
  const Loop sq = test::rect(0, 0, 2, 1);
  CHECK(signed_area(sq) == Approx(2));
  CHECK(perimeter(sq) == Approx(6));
  CHECK(point_in_loop(sq, {1, 0.5}));
  CHECK_FALSE(point_in_loop(sq, {3, 0.5}));
  CHECK(loop_distance(sq, {1, 2}) == Approx(1));
  CHECK(segment_segment_distance({0, 0}, {1, 0}, {0, 1}, {1, 1}) == Approx(1));
  CHECK(segment_segment_distance({0, 0}, {1, 1}, {0, 1}, {1, 0}) == 0.0);
}

TEST_CASE("largest inscribed circle", "[domain]") {
  const Circle c = largest_inscribed_circle(test::circle({3, -2}, 0.5, 128));
  CHECK(std::abs(c.center - cd(3, -2)) < 5e-3);
  CHECK(c.radius == Approx(0.5).epsilon(0.01));
  // A rectangle: radius is half the short side, centre on the long axis.
  const Circle r = largest_inscribed_circle(test::rect(0, 0, 4, 1));
  CHECK(r.radius == Approx(0.5).epsilon(0.01));
  CHECK(r.center.imag() == Approx(0.5).epsilon(0.01));
  // An L-shape: the circle lies in the bigger square part.
  const Circle l = largest_inscribed_circle({{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {0, 1}});
  // It touches x = 3, y = 0 and the reflex vertex (2, 1): r = √2 / (1 + √2).
  CHECK(l.radius == Approx(std::sqrt(2.0) / (1 + std::sqrt(2.0))).margin(0.005));
  CHECK(point_in_loop({{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {0, 1}}, l.center));
}

TEST_CASE("subdivide_edges splits long edges and keeps the outline", "[domain]") {
  const Loop sq = test::rect(0, 0, 2, 1);
  const Loop s = subdivide_edges(sq, 0.25);
  CHECK(s.size() == 24);  // 8 + 4 + 8 + 4 parts
  CHECK(signed_area(s) == Approx(2));
  for (size_t i = 0; i < s.size(); ++i) CHECK(std::abs(s[(i + 1) % s.size()] - s[i]) <= 0.25 + 1e-12);
  CHECK_THROWS_AS(subdivide_edges(sq, 0), InputError);
}
