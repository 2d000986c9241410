// Certificate soundness on every bundled shape (issue #10; the full campaign, ≥ 10,000
// maps per shape, is bench/soundness_campaign): random maps near the fold boundary —
// coefficient perturbations and handle drags carried past the keyframes — are
// certified and compared with a dense brute-force check. No map the dense check finds
// folded may be certified, and every certified lower bound of σ2 must hold.
#include <catch2/catch.hpp>

#include <filesystem>

#include "hsi/scene_io.h"
#include "soundness.h"

using namespace hsi;

TEST_CASE("soundness: never certifies a folded map, on every bundled shape", "[certificate][soundness][long]") {
  std::vector<std::filesystem::path> scenes;
  for (const auto& e : std::filesystem::directory_iterator(HSI_ASSETS_DIR))
    if (e.path().extension() == ".json") scenes.push_back(e.path());
  std::sort(scenes.begin(), scenes.end());
  REQUIRE(scenes.size() >= 10);
  soundness::Tally all;
  for (const auto& path : scenes) {
    Scene scene = load_scene(path);
    const auto setup = make_shape_setup(scene, 2000);
    std::vector<HarmonicMap> keys;
    for (const Keyframe& k : scene.keyframes)
      if (k.coefficients) keys.push_back(*k.coefficients);
    soundness::Options o;
    o.maps = 24;
    o.dense = 20000;
    o.coarse = 2000;
    o.seed = 17;
    const soundness::Tally t = soundness::run(*setup, keys, o, [&](const HarmonicMap&, const CertificateResult& c,
                                                                   const soundness::DenseCheck::Verdict& d, double) {
      if (c.certified && !d.injective) FAIL_CHECK(path.filename() << ": certified, but the dense check finds a fold (gap " << d.min_gap << ", winding " << d.winding << ")");
    });
    INFO(path.filename() << ": " << t.maps << " maps, " << t.certified << " certified, " << t.dense_injective << " injective");
    CHECK(t.maps == o.maps);
    CHECK(t.certified_but_folded == 0);
    CHECK(t.bound_violations == 0);
    all.add(t);
  }
  INFO(all.maps << " maps: " << all.certified << " certified, " << all.dense_injective << " injective by the dense check, "
                << all.injective_not_certified << " injective but not certified");
  // The maps straddle the fold boundary: both verdicts occur, and the certificate proves most injective ones.
  CHECK(all.certified > all.maps / 5);
  CHECK(all.dense_injective < all.maps);
  CHECK(all.certified_but_folded == 0);
  CHECK(all.injective_not_certified < all.dense_injective / 2);
}
