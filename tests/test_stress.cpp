// A slice of the Newton stress corpus (bench/stress/, issue #20) in the test suite:
// six sequences authored from their handles and targets (solve_scene_keyframes) at
// |G| = 2000, interpolated at 20 frames per keyframe interval with the default
// options (PartProj, cap 100). Every frame must be certified and converged, and none
// may reach the iteration cap. bench_stress runs the whole corpus.
//
// Run them alone with   build/tests/hsi_tests "[stress]"
//
// Before the Newton fix of issue #20 (the rotation freed in projected systems), three
// of them stalled at the iteration cap: annulus/hinge, glyph_B/scale and fork/scale.
#include <catch2/catch.hpp>

#include "hsi/interpolation.h"
#include "stress_corpus.h"

using namespace hsi;

namespace {

const stress::Corpus& corpus() {
  static const stress::Corpus c = stress::load_corpus(HSI_STRESS_DIR "/corpus.json");
  return c;
}

void run_slice(const std::string& id) {
  const stress::Corpus& c = corpus();
  const auto q = std::find_if(c.sequences.begin(), c.sequences.end(), [&](const stress::Sequence& s) { return s.id == id; });
  REQUIRE(q != c.sequences.end());
  const Scene shape = stress::load_shape(c, c.shape(q->shape));
  Scene scene = stress::sequence_scene(shape, *q, 2000);
  const auto setup = make_shape_setup(scene, 2000);
  const stress::Authored a = stress::author(scene, *setup);
  REQUIRE(a.maps.size() == q->targets.size());

  const InterpolationOptions options;
  Interpolator interp(*setup, a.times, a.maps, options);
  const int intervals = static_cast<int>(a.times.size()) - 1;
  int frames = 0, uncertified = 0, not_converged = 0, at_cap = 0, max_it = 0;
  for (const FrameResult& f : interp.sequence(20 * intervals + 1)) {
    if (f.keyframe) continue;
    ++frames;
    uncertified += !f.certified;
    not_converged += !f.converged;
    at_cap += f.iterations >= options.max_iterations || !f.converged;
    max_it = std::max(max_it, f.iterations);
  }
  INFO(id << ": " << frames << " frames, " << uncertified << " uncertified, " << not_converged << " not converged, " << at_cap
          << " at the iteration cap, most iterations " << max_it << "; " << a.unreached << " keyframes unreached");
  CHECK(uncertified == 0);
  CHECK(not_converged == 0);
  CHECK(at_cap == 0);
}

}  // namespace

// Pass today.
TEST_CASE("stress slice: grid_2/issue (the issue's 2 x 2 grid of holes, right side turned 0.6 rad)", "[stress]") {
  run_slice("grid_2/issue");
}
TEST_CASE("stress slice: letter_b/hinge (thin B, the top turned)", "[stress]") { run_slice("letter_b/hinge"); }
TEST_CASE("stress slice: chain/hinge (four thin rings, the end turned)", "[stress]") { run_slice("chain/hinge"); }

// These stalled at the iteration cap before the Newton fix of issue #20.
TEST_CASE("stress slice: annulus/hinge (a part turned past 100 deg)", "[stress]") { run_slice("annulus/hinge"); }
TEST_CASE("stress slice: glyph_B/scale (posed first keyframe, scale 0.6 to 1.6 with a large turn)", "[stress]") {
  run_slice("glyph_B/scale");
}
TEST_CASE("stress slice: fork/scale (thin tines, posed first keyframe, scale change with a large turn)", "[stress]") {
  run_slice("fork/scale");
}
