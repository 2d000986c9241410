// Numerical robustness (issue #10): a scene scaled by 1e-3 or 1e4, or moved far from
// the origin, gives the same frames after undoing the scaling and translation; and a
// scene whose keyframes force a hard case never has a frame called good that is not,
// in any output (frames, frames file, report, baked file).
#include <catch2/catch.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/gltf_export.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"
#include "soundness.h"

using namespace hsi;

namespace {

// w ↦ s w + c for a shape's loops, points, and a map's coefficients over the moved cage:
// the moved map is f'(s w + c) = s f(w) + c. Cauchy coordinates are invariant under
// similarities; the log columns gain the constant log s, which a translation absorbs.
struct Similarity {
  double s;
  cd c;
  cd operator()(cd w) const { return s * w + c; }
  Loop operator()(const Loop& l) const {
    Loop out;
    for (const cd& p : l) out.push_back((*this)(p));
    return out;
  }
};

Scene move_scene(const Scene& in, const Similarity& T) {
  Scene s = in;
  s.shape.outer = T(in.shape.outer);
  for (Loop& h : s.shape.holes) h = T(h);
  REQUIRE(in.cage.has_value());
  for (Loop& l : s.cage->loops) l = T(l);
  for (cd& p : s.cage->hole_points) p = T(p);
  for (cd& h : s.handles) h = T(h);
  if (s.texture_rect) {
    const cd a = T(cd((*in.texture_rect)[0], (*in.texture_rect)[1])), b = T(cd((*in.texture_rect)[2], (*in.texture_rect)[3]));
    s.texture_rect = std::array<double, 4>{a.real(), a.imag(), b.real(), b.imag()};
  }
  for (size_t k = 0; k < s.keyframes.size(); ++k) {
    Keyframe& key = s.keyframes[k];
    for (cd& t : key.targets) t = T(t);
    if (!key.coefficients) continue;
    const HarmonicMap& m = *in.keyframes[k].coefficients;
    HarmonicMap moved{T.s * m.phi, T.s * m.psi};
    // Fix the constant: compare at one point of the shape.
    const cd w = in.shape.outer[0];
    const cd want = T(evaluate_map(*in.cage, m, std::vector<cd>{w}).f(0));
    const cd have = evaluate_map(*s.cage, moved, std::vector<cd>{T(w)}).f(0);
    key.coefficients = transform_image(*s.cage, moved, 1.0, want - have);
  }
  return s;
}

}  // namespace

namespace {
void check_invariance(const std::vector<Similarity>& moves) {
  Scene base = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json");
  SceneSequenceOptions o;
  o.frames = 5;
  o.samples = 1000;
  Scene b0 = base;
  const SceneSequence ref = interpolate_scene(b0, o);
  REQUIRE(ref.uncertified() == 0);
  // Points where the frames are compared: the boundary samples.
  const std::vector<cd>& pts = ref.setup->G.points;
  const double size = ref.setup->size;
  for (const Similarity& T : moves) {
    INFO("scale " << T.s << ", translation " << T.c);
    {
      Scene moved = move_scene(base, T);
      const SceneSequence seq = interpolate_scene(moved, o);
      REQUIRE(seq.frames.size() == ref.frames.size());
      std::vector<cd> moved_pts;
      for (const cd& p : pts) moved_pts.push_back(T(p));
      double worst = 0;
      for (size_t i = 0; i < seq.frames.size(); ++i) {
        const FrameResult& a = ref.frames[i];
        const FrameResult& b = seq.frames[i];
        CHECK(b.certified == a.certified);
        CHECK(b.iterations == a.iterations);
        CHECK(b.t == a.t);
        const VectorXcd fa = evaluate_map(ref.setup->cage, a.map, pts).f;
        const VectorXcd fb = evaluate_map(seq.setup->cage, b.map, moved_pts).f;
        for (Eigen::Index k = 0; k < fa.size(); ++k) worst = std::max(worst, std::abs((fb(k) - T.c) / T.s - fa(k)) / size);
        // Distortion is invariant under similarities of domain and image.
        CHECK(b.distortion.conformal_max == Approx(a.distortion.conformal_max).epsilon(1e-8));
        CHECK(b.distortion.sigma2_min == Approx(a.distortion.sigma2_min).epsilon(1e-8));
      }
      INFO("largest difference " << worst << " of the shape's size");
      CHECK(worst < 1e-8);
    }
  }
}

}  // namespace

TEST_CASE("robustness: scaled scenes give the same frames", "[robustness]") {
  check_invariance({Similarity{1e-3, 0}, Similarity{1e4, 0}});
}

// Far from the origin the outer loop's coefficients carry the offset; the pose of a
// frame must take it out exactly (Interpolator::pose_of), not through sums that
// reproduce constants only to rounding (that cost ~1e-4 of the size at 1e5–1e6).
TEST_CASE("robustness: translated scenes give the same frames", "[robustness]") {
  check_invariance({Similarity{1, cd(3e5, -7e5)}, Similarity{1e-3, cd(-2e3, 5e2)}, Similarity{1e2, cd(-4e6, 2e6)}});
}

TEST_CASE("robustness: a hard case never passes an uncertified frame off as good", "[robustness]") {
  // Keyframe 1 is a map barely short of folding: a handle drag from the scene's first
  // keyframe carried on to 99% of the fold boundary (dense check), itself certified.
  Scene scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json");
  scene.keyframes.resize(2);
  auto setup = scene_setup(scene, 1000);
  const MapSpace& space = setup->map_space;
  const Eigen::VectorXd x0 = space.reduce(*scene.keyframes[0].coefficients).x;
  const Eigen::VectorXd dir = space.reduce(*scene.keyframes[1].coefficients).x - x0;
  const soundness::DenseCheck dense(setup->shape, setup->cage, 20000);
  double lo = 1, hi = 2;
  while (dense.check(space.expand(x0 + hi * dir)).injective && hi < 1e3) lo = hi, hi *= 2;
  REQUIRE(hi < 1e3);
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (dense.check(space.expand(x0 + mid * dir)).injective ? lo : hi) = mid;
  }
  double s = 0.99 * lo;
  HarmonicMap hard = space.expand(x0 + s * dir);
  while (!setup->certifier.certify(hard).certified) hard = space.expand(x0 + (s *= 0.98) * dir);
  INFO("keyframe 1 at " << s / lo << " of the fold boundary");
  scene.keyframes[1].coefficients = hard;
  scene.keyframes[1].targets.clear();
  SceneSequenceOptions o;
  o.frames = 9;
  o.interpolation.max_iterations = 3;  // few iterations: frames the line search cannot finish
  const SceneSequence seq = interpolate_scene(scene, o, {}, nullptr, setup);
  const FrameFile ff = decode_frames(encode_frames(seq.frame_file()), "hard.hsif");
  const nlohmann::json report = nlohmann::json::parse(report_json(scene, seq));
  const std::string baked = encode_baked(setup->shape, ff);
  hsib_sequence* hs = nullptr;
  REQUIRE(hsib_open_memory(baked.data(), baked.size(), &hs, nullptr, 0) == HSIB_OK);
  int certified = 0;
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const FrameResult& f = seq.frames[i];
    INFO("frame " << i << " t = " << f.t << ": " << f.message);
    // The frame's verdict is the certificate's on the map that is output, re-run independently…
    const CertificateResult again = setup->certifier.certify(ff.frames[i].map);
    CHECK(again.certified == f.certified);
    // … and a certified frame is injective by the dense check too.
    if (f.certified) CHECK(dense.check(ff.frames[i].map).injective);
    certified += f.certified;
    // Every output says the same.
    CHECK(ff.frames[i].certified == f.certified);
    CHECK(report["frames"][i]["certified"].get<bool>() == f.certified);
    uint32_t flags = 0;
    REQUIRE(hsib_frame_info(hs, static_cast<uint32_t>(i), nullptr, &flags) == HSIB_OK);
    CHECK(((flags & HSIB_FRAME_CERTIFIED) != 0) == f.certified);
    CHECK(((flags & HSIB_FRAME_CONVERGED) != 0) == f.converged);
  }
  hsib_close(hs);
  CHECK(report["summary"]["uncertified"].get<int>() == seq.uncertified());
  CHECK(certified == static_cast<int>(seq.frames.size()) - seq.uncertified());
  // Uncertified frames are never exported as good.
  if (seq.uncertified() > 0) CHECK_THROWS_AS(encode_glb(scene, ff), InputError);
}

