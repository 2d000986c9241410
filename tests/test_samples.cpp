// Boundary samples G (uniform by arc length, split by loop length) and the subset H.
#include <catch2/catch.hpp>

#include "hsi/samples.h"
#include "test_shapes.h"

using namespace hsi;

TEST_CASE("samples are uniform by arc length and split by loop length", "[samples]") {
  const Shape s = test::annulus(1.0, 0.5, 200);
  const BoundarySamples g = sample_boundary(s, 3000);
  REQUIRE(g.size() == 3000);
  const double L0 = perimeter(s.outer), L1 = perimeter(s.holes[0]);
  const int n0 = g.loop_begin[1] - g.loop_begin[0], n1 = g.loop_begin[2] - g.loop_begin[1];
  CHECK(n0 + n1 == 3000);
  CHECK(static_cast<double>(n0) / n1 == Approx(L0 / L1).epsilon(0.01));
  // Every sample on its loop's boundary; consecutive spacing ≈ L/n.
  for (size_t i = 0; i < g.size(); ++i) CHECK(loop_distance(s.loop(g.loop[i]), g.points[i]) < 1e-12);
  for (int i = g.loop_begin[0] + 1; i < g.loop_begin[1]; ++i)
    CHECK(std::abs(g.points[static_cast<size_t>(i)] - g.points[static_cast<size_t>(i - 1)]) == Approx(L0 / n0).epsilon(0.01));
}

TEST_CASE("samples are deterministic and H is a spread-out subset", "[samples]") {
  const Shape s = test::bar_with_holes();
  const BoundarySamples a = sample_boundary(s, 10000), b = sample_boundary(s, 10000);
  CHECK(a.points == b.points);
  const std::vector<int> h = hessian_subset(a, 0.2);
  CHECK(h.size() == 2000);
  CHECK(std::is_sorted(h.begin(), h.end()));
  CHECK(std::adjacent_find(h.begin(), h.end()) == h.end());
  // Each loop receives its share of H.
  for (int l = 0; l < s.loop_count(); ++l) {
    const auto in_loop = std::count_if(h.begin(), h.end(), [&](int i) { return a.loop[static_cast<size_t>(i)] == l; });
    const int share = a.loop_begin[static_cast<size_t>(l) + 1] - a.loop_begin[static_cast<size_t>(l)];
    CHECK(static_cast<double>(in_loop) == Approx(0.2 * share).margin(2));
  }
  CHECK(hessian_subset(a, 1.0).size() == a.size());
  CHECK_THROWS_AS(hessian_subset(a, 0.0), InputError);
  CHECK_THROWS_AS(sample_boundary(s, 0), InputError);
}

TEST_CASE("H keeps a minimum number of samples on small loops", "[samples]") {
  const Shape s = test::annulus(1.0, 0.05, 64);  // a tiny hole: about 5% of the boundary
  const BoundarySamples g = sample_boundary(s, 1000);
  const auto plain = hessian_subset(g, 0.05);
  const auto guarded = hessian_subset(g, 0.05, {0, 30});
  auto on_hole = [&](const std::vector<int>& h) {
    return std::count_if(h.begin(), h.end(), [&](int i) { return g.loop[static_cast<size_t>(i)] == 1; });
  };
  CHECK(on_hole(plain) < 30);
  CHECK(on_hole(guarded) == 30);
  CHECK(hessian_subset(g, 0.05, {0, 100000}).size() == plain.size() - static_cast<size_t>(on_hole(plain)) +
                                                           static_cast<size_t>(g.loop_begin[2] - g.loop_begin[1]));
}
