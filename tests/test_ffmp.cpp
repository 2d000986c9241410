// The FFMP baseline (engine/baselines, Kircher & Garland 2008: connection maps blended
// linearly, frames and positions from two sparse solves): keyframes reproduced, rigid and
// similarity motions kept, the frame solve's optimality, its linear-blend shrink, bundled
// scenes' keyframes, and bad input refused with a message naming it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "baseline_meshes.h"
#include "hsi/baselines/arap.h"
#include "hsi/baselines/ffmp.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"

using namespace hsi;
using namespace hsi::baselines;
using namespace hsi::test::mesh;

namespace {

const auto wobble = [](cd z) { return std::polar(1.0, 0.4) * bend(z, 0.6) + 0.15 * cd(z.imag() * z.imag(), 0.2 * z.real()) + cd(0.3, -0.2); };

}  // namespace

TEST_CASE("FFMP reproduces every keyframe at its time", "[ffmp]") {
  const TriMesh m = bar_mesh(300);
  const double size = mesh_size(m);
  const std::vector<MeshKeyframe> kf{{0, apply(m, [](cd z) { return 0.7 * z + cd(0.1, 0.2); })},
                                     {1, apply(m, wobble)},
                                     {3, apply(m, [](cd z) { return std::polar(1.2, 2.9) * bend(z, -0.8); })}};
  const FfmpInterpolation ffmp(m, kf);
  CHECK(ffmp.keyframe_count() == 3);
  CHECK(ffmp.t_begin() == 0);
  CHECK(ffmp.t_end() == 3);
  CHECK(ffmp.anchors().size() == 1);
  for (const MeshKeyframe& k : kf) {
    CAPTURE(k.time);
    const FfmpFrame f = ffmp.frame(k.time);
    CHECK(max_distance(f.positions, k.positions) < 1e-10 * size);
    CHECK(f.frame_residual < 1e-12);
    CHECK(f.position_residual < 1e-12);
  }
  // Clamped outside the keyframes' range.
  CHECK(max_distance(ffmp.positions(-1), kf[0].positions) < 1e-10 * size);
  CHECK(max_distance(ffmp.positions(7), kf[2].positions) < 1e-10 * size);
  // In between: blended connection maps are no longer those of any set of frames.
  const FfmpFrame mid = ffmp.frame(2);
  CHECK(mid.frame_residual > 1e-6);
  CHECK(mid.position_residual > 0);
  for (cd p : mid.positions) REQUIRE((std::isfinite(p.real()) && std::isfinite(p.imag())));
}

TEST_CASE("FFMP interpolates rigid and similarity motions as such, turning linearly", "[ffmp]") {
  const TriMesh m = bar_mesh(300);
  const double size = mesh_size(m);
  const cd c0 = centroid(m, m.vertices);
  for (double k : {1.0, 1.8}) {
    CAPTURE(k);
    // 2.8 rad (under π: the anchor takes the short way), then 2.8 rad more: 5.6 rad in all.
    const double turn = 2.8;
    const cd c1(2, 1), c2(-1, 3);
    auto pose = [&](double scale, double angle, cd c) {
      return apply(m, [&](cd z) { return scale * std::polar(1.0, angle) * (z - c0) + c; });
    };
    const FfmpInterpolation ffmp(m, {{0, m.vertices}, {1, pose(k, turn, c1)}, {2, pose(1, 2 * turn, c2)}});
    for (double t : {0.0, 0.3, 0.5, 1.0, 1.25, 1.9, 2.0}) {
      CAPTURE(t);
      const int seg = t <= 1 ? 0 : 1;
      const double s = t - seg;
      const double scale = seg == 0 ? (1 - s) + s * k : (1 - s) * k + s;
      const cd c = seg == 0 ? (1 - s) * c0 + s * c1 : (1 - s) * c1 + s * c2;
      const FfmpFrame f = ffmp.frame(t);
      CHECK(max_distance(f.positions, pose(scale, (seg + s) * turn, c)) < 1e-9 * size);
      CHECK(f.frame_residual < 1e-12);
      const MeshDistortion d = mesh_distortion(m, f.positions);
      CHECK(d.max_kappa < 1 + 1e-9);
    }
  }
}

TEST_CASE("FFMP's linear blend of connection maps shrinks a bend far more than ARAP", "[ffmp]") {
  // A bar bent by ±1.4 rad per unit: across an edge of length h the connection maps turn
  // from e^{−i 1.4 h} to e^{+i 1.4 h}, and their linear blend at s = ½ is cos(1.4 h)·I: the
  // frames shrink edge by edge away from the anchor (the paper's 'unnatural scaling', its
  // Figs 4 and 10). ARAP interpolates the angles. Measured on the total signed area.
  const TriMesh m = bar_mesh(400);
  const std::vector<MeshKeyframe> kf{{0, apply(m, [](cd z) { return bend(z, -1.4); })}, {1, apply(m, [](cd z) { return bend(z, 1.4); })}};
  const FfmpInterpolation ffmp(m, kf);
  const ArapInterpolation arap(m, kf);
  auto area = [&](std::span<const cd> x) {
    double a = 0;
    for (const auto& t : m.triangles) a += signed_area(x, t);
    return a;
  };
  const double key_area = area(kf[0].positions), ffmp_area = area(ffmp.positions(0.5)), arap_area = area(arap.positions(0.5));
  std::printf("FFMP bend: keyframe area %.4f, at t = 0.5 FFMP %.4f, ARAP %.4f\n", key_area, ffmp_area, arap_area);
  CHECK(ffmp_area < 0.8 * arap_area);
  CHECK(ffmp_area > 0);
}

TEST_CASE("FFMP: the anchor option and bad input refused with a message naming it", "[ffmp]") {
  const TriMesh m = bar_mesh(100);
  const double size = mesh_size(m);
  const std::vector<cd> rest = m.vertices, k1 = apply(m, wobble);
  // Any anchor reproduces the keyframes.
  const FfmpInterpolation other(m, {{0, rest}, {1, k1}}, {.anchor_triangle = 3});
  CHECK(other.anchors() == std::vector<int>{3});
  CHECK(max_distance(other.positions(1), k1) < 1e-10 * size);
  CHECK(max_distance(other.positions(0), rest) < 1e-10 * size);

  CHECK_THAT(error_of([&] { FfmpInterpolation(m, {{0, rest}}); }), Catch::Contains("at least 2 keyframes"));
  CHECK_THAT(error_of([&] { FfmpInterpolation(m, {{0, rest}, {-1, rest}}); }),
             Catch::Contains("FFMP keyframe 1") && Catch::Contains("increase"));
  CHECK_THAT(error_of([&] { FfmpInterpolation(m, {{0, rest}, {1, apply(m, [](cd z) { return std::conj(z); })}}); }),
             Catch::Contains("FFMP keyframe 1") && Catch::Contains("flipped"));
  std::vector<cd> nan = rest;
  nan[5] = {std::nan(""), 0};
  CHECK_THAT(error_of([&] { FfmpInterpolation(m, {{0, rest}, {1, nan}}); }), Catch::Contains("vertex 5") && Catch::Contains("not finite"));
  CHECK_THAT(error_of([&] { FfmpInterpolation(m, {{0, rest}, {1, rest}}, {.anchor_triangle = m.triangle_count()}); }),
             Catch::Contains("anchor_triangle"));
  const FfmpInterpolation ok(m, {{0, rest}, {1, rest}});
  CHECK_THAT(error_of([&] { (void)ok.positions(std::nan("")); }), Catch::Contains("NaN"));
}

TEST_CASE("FFMP on bundled scenes: keyframes exact, in-betweens finite", "[ffmp][assets]") {
  for (const char* name : {"annulus", "arm"}) {
    CAPTURE(name);
    Scene scene = load_scene(std::string(HSI_ASSETS_DIR) + "/" + name + ".json");
    const auto setup = scene_setup(scene);
    solve_scene_keyframes(scene, *setup);
    const TriMesh m = triangulate(scene.shape, {.max_edge = edge_for_vertex_count(scene.shape, 2000)});
    const double size = mesh_size(m);
    std::vector<MeshKeyframe> kf;
    for (const Keyframe& k : scene.keyframes) kf.push_back({k.time, map_points(setup->cage, *k.coefficients, m.vertices)});
    const FfmpInterpolation ffmp(m, kf);
    for (const MeshKeyframe& k : kf) CHECK(max_distance(ffmp.positions(k.time), k.positions) < 1e-9 * size);
    double worst_kappa = 1;
    int flipped = 0;
    for (size_t k = 0; k + 1 < kf.size(); ++k)
      for (double s : {0.25, 0.5, 0.75}) {
        const FfmpFrame f = ffmp.frame((1 - s) * kf[k].time + s * kf[k + 1].time);
        for (cd p : f.positions) REQUIRE((std::isfinite(p.real()) && std::isfinite(p.imag())));
        const MeshDistortion d = mesh_distortion(m, f.positions);
        flipped += d.flipped;
        worst_kappa = std::max(worst_kappa, d.max_kappa);
      }
    std::printf("FFMP %s (%d vertices): in-betweens max κ %.4f, flipped %d\n", name, m.vertex_count(), worst_kappa, flipped);
  }
}
