// Certificate soundness campaign (issue #10): on every bundled shape, ≥ 10,000 random
// maps near the fold boundary (random coefficient perturbations from the identity or a
// keyframe, and handle drags carried on past the keyframes; tests/soundness.h), each
// certified by the CPU certificate and compared with a dense brute-force check
// (|f_z| − |f_zbar| at --dense boundary points plus the polygon vertices, and the
// winding of f_z). Prints, per shape: maps, certified, dense-injective,
// certified-but-folded (must be 0), injective-but-not-certified (the certificate's
// conservativeness), and where the uncertified injective maps lie relative to the
// fold boundary t* along their direction.
//
//   soundness_campaign [--maps 10000] [--dense 40000] [--samples 0] [--shapes a,b] [--seed 1]
// Use OMP_NUM_THREADS=1 to keep it to one core.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "hsi/scene_io.h"
#include "soundness.h"

using namespace hsi;

int main(int argc, char** argv) {
  CLI::App app{"Certificate soundness campaign: random maps near the fold boundary vs a dense check"};
  int maps = 10000, dense = 40000, samples = 0;
  unsigned seed = 1;
  std::string shapes, assets = HSI_ASSETS_DIR;
  app.add_option("--maps", maps, "Maps per shape")->capture_default_str();
  app.add_option("--dense", dense, "Dense check points on the boundary")->capture_default_str();
  app.add_option("--samples", samples, "Certificate samples |G| (0: the scene's)")->capture_default_str();
  app.add_option("--shapes", shapes, "Comma-separated scene names (default: every bundled scene)");
  app.add_option("--assets", assets, "Folder of scenes")->capture_default_str();
  app.add_option("--seed", seed, "Random seed")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::vector<std::filesystem::path> scenes;
  for (const auto& e : std::filesystem::directory_iterator(assets))
    if (e.path().extension() == ".json") scenes.push_back(e.path());
  std::sort(scenes.begin(), scenes.end());
  if (!shapes.empty()) {
    std::vector<std::filesystem::path> keep;
    std::stringstream ss(shapes);
    for (std::string name; std::getline(ss, name, ',');)
      for (const auto& p : scenes)
        if (p.stem() == name) keep.push_back(p);
    scenes = keep;
  }
  std::printf("%-16s %7s %6s %9s %9s %10s %12s %14s %12s %8s\n", "shape", "maps", "|G|", "certified", "injective",
              "cert+fold", "inj not cert", "not cert in", "bound viol.", "s");
  std::fflush(stdout);
  soundness::Tally all;
  for (const auto& path : scenes) {
    const auto t0 = std::chrono::steady_clock::now();
    Scene scene = load_scene(path);
    const auto setup = make_shape_setup(scene, samples);
    std::vector<HarmonicMap> keys;
    for (const Keyframe& k : scene.keyframes)
      if (k.coefficients) keys.push_back(*k.coefficients);
    soundness::Options o;
    o.maps = maps;
    o.dense = dense;
    o.seed = seed;
    // Where the injective-but-uncertified maps lie: their t / t* (1 = the fold boundary).
    double lowest_ratio = 2;
    const soundness::Tally t = soundness::run(*setup, keys, o, [&](const HarmonicMap&, const CertificateResult& c,
                                                                   const soundness::DenseCheck::Verdict& d, double ratio) {
      if (!c.certified && d.injective) lowest_ratio = std::min(lowest_ratio, ratio);
      if (c.certified && !d.injective)
        std::fprintf(stderr, "%s: CERTIFIED BUT FOLDED at t/t* = %.6f: dense gap %.3e, winding %d\n", path.stem().c_str(), ratio,
                     d.min_gap, d.winding);
    });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char range[32] = "-";
    if (t.injective_not_certified > 0) std::snprintf(range, sizeof range, "t/t* >= %.3f", lowest_ratio);
    std::printf("%-16s %7ld %6zu %9ld %9ld %10ld %5ld (%4.1f%%) %14s %12ld %8.0f\n", path.stem().c_str(), t.maps, setup->G.size(),
                t.certified, t.dense_injective, t.certified_but_folded, t.injective_not_certified,
                t.dense_injective ? 100.0 * static_cast<double>(t.injective_not_certified) / static_cast<double>(t.dense_injective) : 0.0, range, t.bound_violations, s);
    std::fflush(stdout);
    all.add(t);
  }
  std::printf("%-16s %7ld %6s %9ld %9ld %10ld %5ld (%4.1f%%) %14s %12ld\n", "all", all.maps, "", all.certified, all.dense_injective,
              all.certified_but_folded, all.injective_not_certified,
              all.dense_injective ? 100.0 * static_cast<double>(all.injective_not_certified) / static_cast<double>(all.dense_injective) : 0.0, "", all.bound_violations);
  return all.certified_but_folded == 0 && all.bound_violations == 0 ? 0 : 1;
}
