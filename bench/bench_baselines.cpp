// Benchmark of the mesh baselines (engine/baselines: ARAP, FFMP, GE) on a bundled scene's
// render mesh: set-up time, then per frame the time of each method, GE's Newton
// iterations and energy, and each frame's worst per-triangle conformal distortion and
// flipped triangles. Frames are those of a sequence like `hsi compare`'s (--frames over
// the keyframes' range), a run of --run consecutive ones from --first; GE warm-starts
// each from the previous one (the first from the nearest keyframe). One thread.
// Timings only: never run by the test suite.
#include "hsi/stopwatch.h"
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "bench_scenes.h"
#include "hsi/baselines/arap.h"
#include "hsi/baselines/ffmp.h"
#include "hsi/baselines/ge.h"
#include "hsi/triangulate.h"

using namespace hsi;
using namespace hsi::baselines;

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Mesh baselines (ARAP, FFMP, GE): per-frame time and GE iterations"};
  std::string scene_path = std::string(HSI_ASSETS_DIR) + "/bar_holes.json";
  int vertices = 8000, frames = 100, first = 25, run = 6;
  GeOptions ge_options;
  app.add_option("--scene", scene_path, "Scene file")->capture_default_str();
  app.add_option("--vertices", vertices, "Render mesh vertices (about)")->capture_default_str();
  app.add_option("--frames", frames, "Frames of the whole sequence over the keyframes' range (as hsi compare --frames)")
      ->capture_default_str();
  app.add_option("--first", first, "First frame of the run (0-based)")->capture_default_str();
  app.add_option("--run", run, "Consecutive frames timed")->capture_default_str();
  app.add_option("--ge-tolerance", ge_options.tolerance, "GE's relative convergence tolerance (GeOptions::tolerance)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (frames < 2 || first < 0 || run < 1 || first + run > frames) {
    std::fprintf(stderr, "bench_baselines: need frames ≥ 2, first ≥ 0, run ≥ 1, first + run ≤ frames\n");
    return 2;
  }

  const bench::Loaded L = bench::load(scene_path, 0, 0);
  const TriMesh mesh = triangulate(L.scene.shape, {.max_edge = edge_for_vertex_count(L.scene.shape, vertices)});
  std::vector<MeshKeyframe> keys;
  for (size_t k = 0; k < L.maps.size(); ++k) keys.push_back({L.times[k], map_points(L.setup->cage, L.maps[k], mesh.vertices)});
  std::printf("scene %s: %zu keyframes; mesh %d vertices, %d triangles\n", L.name.c_str(), keys.size(), mesh.vertex_count(),
              mesh.triangle_count());

  auto t0 = Clock::now();
  const ArapInterpolation arap(mesh, keys);
  const double arap_setup = ms_since(t0);
  t0 = Clock::now();
  const FfmpInterpolation ffmp(mesh, keys);
  const double ffmp_setup = ms_since(t0);
  t0 = Clock::now();
  const GeInterpolation ge(mesh, keys, ge_options);
  const double ge_setup = ms_since(t0);
  std::printf("set-up: ARAP %.0f ms, FFMP %.0f ms, GE %.0f ms (GE tolerance %g)\n", arap_setup, ffmp_setup, ge_setup,
              ge_options.tolerance);

  std::vector<double> times;
  for (int i = first; i < first + run; ++i)
    times.push_back(keys.front().time + (keys.back().time - keys.front().time) * i / (frames - 1));

  std::printf("%6s %8s | %9s %7s | %9s %9s %7s | %9s %5s %10s %5s %7s\n", "frame", "t", "ARAP ms", "max κ", "FFMP ms",
              "(frames)", "max κ", "GE ms", "iter", "energy", "conv", "max κ");
  double arap_sum = 0, ffmp_sum = 0, ge_sum = 0;
  int ge_iterations = 0, ge_min = 1 << 30, ge_max = 0, not_converged = 0, arap_flip = 0, ffmp_flip = 0, ge_flip = 0;
  std::vector<cd> start = keys.front().positions;
  // The warm start of the first frame: GE's own sequence rule (the nearest keyframe).
  for (size_t k = 1; k < keys.size(); ++k)
    if (std::abs(keys[k].time - times[0]) < std::abs(keys[0].time - times[0])) start = keys[k].positions;
  for (size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    t0 = Clock::now();
    const std::vector<cd> a = arap.positions(t);
    const double a_ms = ms_since(t0);
    t0 = Clock::now();
    const FfmpFrame f = ffmp.frame(t);
    const double f_ms = ms_since(t0);
    const GeFrame g = ge.frame(t, start);
    start = g.positions;
    const MeshDistortion da = mesh_distortion(mesh, a), df = mesh_distortion(mesh, f.positions), dg = mesh_distortion(mesh, g.positions);
    std::printf("%6d %8.4f | %9.1f %7.3f | %9.1f %9.1f %7.3f | %9.1f %5d %10.6f %5s %7.3f\n", first + static_cast<int>(i), t, a_ms,
                da.max_kappa, f_ms, f.frames_ms, df.max_kappa, g.ms, g.iterations, g.energy, g.converged ? "yes" : "NO",
                dg.max_kappa);
    arap_sum += a_ms;
    ffmp_sum += f_ms;
    ge_sum += g.ms;
    ge_iterations += g.iterations;
    ge_min = std::min(ge_min, g.iterations);
    ge_max = std::max(ge_max, g.iterations);
    not_converged += g.converged ? 0 : 1;
    arap_flip += da.flipped;
    ffmp_flip += df.flipped;
    ge_flip += dg.flipped;
  }
  const double n = static_cast<double>(times.size());
  std::printf("mean per frame: ARAP %.1f ms, FFMP %.1f ms, GE %.1f ms with %.1f Newton iterations (min %d, max %d, %d not converged)\n",
              arap_sum / n, ffmp_sum / n, ge_sum / n, ge_iterations / n, ge_min, ge_max, not_converged);
  std::printf("flipped triangles over the run: ARAP %d, FFMP %d, GE %d\n", arap_flip, ffmp_flip, ge_flip);
  return 0;
}
