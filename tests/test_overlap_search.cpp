// The overlap check's crossing search kept per checker and refit per check (issue #23):
// the same result as the reference search (check_points_reference, the search made per
// call) on every input, hard cases included; and the sequence that runs the search on a
// thread of its own beside the next solve gives the frames of the one that does not.
#include <catch2/catch.hpp>

#include <numbers>
#include <random>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/overlap.h"
#include "hsi/scene_sequence.h"
#include "frame_compare.h"
#include "random_loops.h"
#include "test_shapes.h"

using namespace hsi;
using hsi::test::random_loops;
using hsi::test::require_same;

namespace {

bool finite(const std::vector<Loop>& loops) {
  for (const Loop& l : loops)
    for (const cd& z : l)
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) return false;
  return true;
}

std::vector<Loop> transformed(std::vector<Loop> loops, double scale, cd offset) {
  for (Loop& l : loops)
    for (cd& z : l) z = scale * z + offset;
  return loops;
}

// A shape's breakpoints with their order shuffled across loops (the layout's slots
// then differ from the image's order).
CertificateSegments interleaved(const CertificateSegments& s, std::mt19937& rng) {
  std::vector<size_t> order(s.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  // Keep each loop's own order (the polylines run through it), interleave the loops.
  std::vector<std::vector<size_t>> by_loop;
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t l = static_cast<size_t>(s.loop[i]);
    if (l >= by_loop.size()) by_loop.resize(l + 1);
    by_loop[l].push_back(i);
  }
  std::vector<size_t> at(by_loop.size(), 0);
  std::uniform_int_distribution<size_t> pick(0, by_loop.size() - 1);
  order.clear();
  while (order.size() < s.size()) {
    const size_t l = pick(rng);
    if (at[l] < by_loop[l].size()) order.push_back(by_loop[l][at[l]++]);
  }
  CertificateSegments out;
  for (size_t i : order) {
    out.points.push_back(s.points[i]);
    out.next.push_back(-1);  // not used by the overlap check
    out.loop.push_back(s.loop[i]);
    out.edge.push_back(s.edge[i]);
  }
  return out;
}

}  // namespace

TEST_CASE("overlap search: the kept hierarchy finds what the reference finds, on random and degenerate polylines",
          "[overlap]") {
  std::mt19937 rng(23);
  int overlapping = 0, cases = 0;
  for (int kind = 0; kind < 6; ++kind)
    for (int points : {12, 90, 600}) {
      const std::vector<Loop> base = random_loops(rng, kind, points);
      for (double scale : {1e-300, 1e-150, 1e-5, 1.0, 1e5, 1e150, 1e300})
        for (cd offset : {cd(0, 0), cd(1e7, -3e7), cd(-1e15, 1e15)}) {
          const std::vector<Loop> loops = transformed(base, scale, scale * offset);
          if (!finite(loops)) continue;  // polyline_overlap leaves those unchecked (below); the reference did not look
          const OverlapResult want = polyline_overlap_reference(loops);
          INFO("kind " << kind << ", " << points << " points, scale " << scale << ", offset " << offset);
          require_same(polyline_overlap(loops), want);
          overlapping += want.overlaps();
          ++cases;
        }
    }
  // The cases are not all of one verdict: the comparison above can fail both ways.
  CHECK(overlapping > cases / 4);
  CHECK(overlapping < cases);
}

TEST_CASE("overlap search: large random polylines, and hand-made hard cases", "[overlap]") {
  std::mt19937 rng(2026);
  for (int kind : {0, 1, 2, 4})
    for (int points : {3000, 12000}) {
      const std::vector<Loop> loops = random_loops(rng, kind, points);
      const OverlapResult want = polyline_overlap_reference(loops);
      INFO("kind " << kind << ", " << points << " points: " << want.crossings << " crossings");
      if (kind == 0) CHECK_FALSE(want.overlaps());
      if (kind == 1 || kind == 2) CHECK(want.crossings > 100);
      require_same(polyline_overlap(loops), want);
    }
  const std::vector<std::vector<Loop>> hard = {
      {},
      {{}},
      {{{0, 0}}, {{1, 1}, {2, 2}}},                              // no loop of 3 points
      {{{0, 0}, {1, 0}, {2, 0}}},                                // flat: every edge on one line
      {{{0, 0}, {2, 0}, {1, 0}, {1, 1}}},                        // a neighbour folding back
      {{{0, 0}, {1, 0}, {2, 0}, {1, 1}}},                        // straight through a vertex: nothing
      {{{0, 0}, {1, 0}, {0, 0}, {0, 1}}},                        // back exactly onto the previous vertex
      {{{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {{4, 1}, {5, 1}, {5, 2}, {4, 2}}},  // a hole touching along an edge
      {{{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {{4, 4}, {5, 4}, {5, 5}}},          // touching at a corner
      {{{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}}},                // a vertex on a non-neighbour edge
      {{{0, 0}, {1, 1e-300}, {2, 0}, {1, -1e-300}}},             // nearly flat: exact signs only
      {{{1e308, 0}, {-1e308, 1e308}, {-1e308, -1e308}}},         // differences overflow
      {{{0, 0}, {1, 0}, {1 + 1e-12, -1e-12}, {1 - 1e-13, 1e-13}, {1, 1}, {0, 1}}},  // merged round-off
  };
  for (size_t k = 0; k < hard.size(); ++k) {
    INFO("hard case " << k);
    require_same(polyline_overlap(hard[k]), polyline_overlap_reference(hard[k]));
  }
  // A point that is not finite: not checked (as the checker's images always were).
  CHECK_FALSE(polyline_overlap({{{0, 0}, {1, 0}, {std::numeric_limits<double>::infinity(), 1}}}).checked);
}

TEST_CASE("overlap search: a checker's image checks equal the reference's, one workspace reused, any slot order",
          "[overlap]") {
  // A C-shaped ring mapped by holomorphic maps that wind it over itself a little more
  // each time (z^p), and the bar with holes under shears and folds: images with and
  // without crossings, of every loop against every other.
  std::mt19937 rng(7);
  for (const Shape& shape : {test::bar_with_holes(), test::annulus(1.0, 0.4, 48)}) {
    const ShapeSetup setup(shape, build_cage(shape), 1500, 0.2);
    const OverlapChecker& checker = setup.overlap;
    const OverlapChecker shuffled(setup.cage, interleaved(checker.breakpoints(), rng));
    OverlapChecker::Workspace w, ws;
    int overlapping = 0;
    for (int k = 0; k < 24; ++k) {
      // f(z) = z + a (z − c)^2 + noise: a fold grows with a.
      const double a = 0.15 * k;
      std::vector<cd> image;
      for (const cd& z : checker.breakpoints().points) {
        const cd d = z - cd(0.3, 0.1);
        image.push_back(z + a * d * d + cd(1e-3 * static_cast<double>(rng() % 7), 0));
      }
      const OverlapResult want = checker.check_points_reference(image);
      INFO("a = " << a << ": " << describe(want));
      require_same(checker.check_points(image, w), want);
      require_same(checker.check_points(image), want);
      overlapping += want.overlaps();
      // The same points in the shuffled checker's order.
      std::vector<cd> permuted;
      const CertificateSegments& s = shuffled.breakpoints();
      for (size_t i = 0; i < s.size(); ++i) permuted.push_back(s.points[i]);
      for (cd& z : permuted) {
        const cd d = z - cd(0.3, 0.1);
        z = z + a * d * d;
      }
      require_same(shuffled.check_points(permuted, ws), shuffled.check_points_reference(permuted));
    }
    CHECK(overlapping > 0);
    CHECK(overlapping < 24);
    // A non-finite image is not checked, as before; a wrong number of points is refused.
    std::vector<cd> bad(checker.breakpoints().points.begin(), checker.breakpoints().points.end());
    bad[bad.size() / 2] = cd(std::numeric_limits<double>::quiet_NaN(), 0);
    require_same(checker.check_points(bad, w), checker.check_points_reference(bad));
    CHECK_FALSE(checker.check_points(bad, w).checked);
    bad.pop_back();
    CHECK_THROWS_WITH(checker.check_points(bad, w), Catch::Matchers::Contains("image points for"));
  }
}

namespace {

std::filesystem::path bent_bar_path() { return std::filesystem::path(HSI_TESTS_DIR) / "scenes" / "bent_bar.json"; }

struct BentBar {
  Scene scene = load_scene(bent_bar_path());
  std::shared_ptr<const ShapeSetup> setup = scene_setup(scene);
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  BentBar() {
    for (const Keyframe& k : scene.keyframes) {
      times.push_back(k.time);
      maps.push_back(*k.coefficients);
    }
  }
};

BentBar& bent_bar() {
  static BentBar b;
  return b;
}

// Each progress call: its index, count and a copy of the frame it was given.
struct Calls {
  std::vector<int> index;
  std::vector<FrameResult> frames;
  std::function<void(const FrameResult&, int, int)> callback() {
    return [this](const FrameResult& f, int i, int n) {
      index.push_back(i);
      CHECK(n == expected);
      frames.push_back(f);
    };
  }
  int expected = 0;
};

// The setup's CPU image of the breakpoints, one point short from call `fail_at` on (a
// backend's evaluator gone wrong): the crossing search refuses such an image.
class ShortImage final : public MeshEvaluator {
 public:
  ShortImage(const ShapeSetup& setup, int fail_at)
      : inner_(make_cpu_mesh_evaluator(setup.cage, setup.overlap.breakpoints().points)), fail_at_(fail_at) {}
  const char* name() const override { return "short"; }
  std::size_t size() const override { return inner_->size(); }
  bool derivatives() const override { return false; }
  void evaluate(const HarmonicMap& map, MapValues& out) override {
    inner_->evaluate(map, out);
    if (++calls_ >= fail_at_) out.f.conservativeResize(out.f.size() - 1);
  }

 private:
  std::unique_ptr<MeshEvaluator> inner_;
  int fail_at_, calls_ = 0;
};

}  // namespace

TEST_CASE("pipelined sequence: the frames and progress calls of the sequence in series, overlapping frames included",
          "[overlap][interpolation]") {
  BentBar& B = bent_bar();
  // Keyframe times exactly (keyframe 1 overlaps itself) and solved frames between.
  const std::vector<double> times = sequence_times(B.times, 0, 3);
  InterpolationOptions series;
  series.pipelined_overlap = false;
  InterpolationOptions pipelined;
  REQUIRE(pipelined.pipelined_overlap);  // the default
  Interpolator a(*B.setup, B.times, B.maps, series), b(*B.setup, B.times, B.maps, pipelined);
  Calls ca, cb;
  ca.expected = cb.expected = static_cast<int>(times.size());
  const std::vector<FrameResult> fa = a.sequence(times, ca.callback());
  const std::vector<FrameResult> fb = b.sequence(times, cb.callback());
  REQUIRE(fa.size() == times.size());
  REQUIRE(fb.size() == times.size());
  int solved_overlapping = 0;
  for (size_t i = 0; i < fa.size(); ++i) {
    require_same(fb[i], fa[i]);
    solved_overlapping += !fa[i].keyframe && fa[i].overlap.overlaps();
    if (!fa[i].keyframe) {
      CHECK(fa[i].overlap.checked);
      CHECK(fb[i].parts.crossings > 0);
      CHECK(fb[i].parts.crossings_wait >= 0);
      CHECK(fa[i].parts.crossings_wait == fa[i].parts.crossings);
    }
  }
  INFO(solved_overlapping << " solved frames overlap");
  CHECK(solved_overlapping > 0);     // the search's result travels through the thread
  CHECK(fa.back().overlap.overlaps());  // keyframe 1
  // Progress: once per frame, in order, with the complete frame (the one returned).
  std::vector<int> in_order(times.size());
  for (size_t i = 0; i < in_order.size(); ++i) in_order[i] = static_cast<int>(i);
  CHECK(ca.index == in_order);
  CHECK(cb.index == in_order);
  for (size_t i = 0; i < cb.frames.size() && i < fb.size(); ++i) {
    require_same(cb.frames[i], fb[i]);
    CHECK(cb.frames[i].parts.crossings == fb[i].parts.crossings);
    CHECK(cb.frames[i].ms == fb[i].ms);
  }
  // Again on the same interpolator (its thread made afresh, its buffers reused): the same.
  const std::vector<FrameResult> again = b.sequence({times[0], times[1]});
  require_same(again[0], fa[0]);
  require_same(again[1], fa[1]);
}

TEST_CASE("pipelined sequence: an exception of the crossing search reaches the caller, after the frames before it",
          "[overlap][interpolation]") {
  // A disc turned and moved: every frame is the identity's shape, solved in an iteration or two.
  const Shape shape = test::disc(1.0, 32);
  const ShapeSetup setup(shape, build_cage(shape), 400, 0.2);
  const HarmonicMap id = identity_map(setup.cage);
  const std::vector<double> key_times{0, 1};
  const std::vector<HarmonicMap> keys{id, transform_image(setup.cage, id, std::polar(1.0, 0.8), cd(0.5, -0.2))};
  const std::vector<double> times = sequence_times(key_times, 6);  // keyframe, 4 solved, keyframe
  const int set_up = static_cast<int>(key_times.size());           // set-up evaluates each keyframe's image once
  for (bool pipelined : {false, true})
    for (int failing : {2, 4}) {  // a solved frame in the middle, the last solved frame
      InterpolationOptions o;
      o.pipelined_overlap = pipelined;
      INFO((pipelined ? "pipelined" : "in series") << ", frame " << failing << "'s image short");
      Interpolator I(setup, key_times, keys, o, nullptr, std::make_unique<ShortImage>(setup, set_up + failing));
      Calls c;
      c.expected = static_cast<int>(times.size());
      CHECK_THROWS_WITH(I.sequence(times, c.callback()), Catch::Matchers::Contains("image points for"));
      CHECK(c.index.size() == static_cast<size_t>(failing));  // frames 0 .. failing − 1, complete
    }
}
