// GPU playback of a baked sequence (shaders/hsib_playback.glsl through Vulkan, as a
// compute pass over every vertex of every instance: hsi/compute/hsib_playback.h)
// against the CPU runtime (hsib_evaluate_blend), in one run: N instances of a
// V-vertex sprite (the shape's triangulation), every instance showing the same blend
// of two frames. CPU: one thread, and all threads over instances. GPU: the pass's
// device time (timestamps) and its wall time with the uniform upload, submit and wait.
// The CPU path would also upload N x V x 8 bytes of positions per frame; the GPU path
// uploads 16 x (R + 2) bytes of uniforms. Prints a table with the ratios.
// --distortion: both paths also compute every vertex's singular values (sigma1, sigma2,
// from derivative rows: hsib_evaluate_blend_distortion, hsib_singular_values in GLSL).
#include "hsi/stopwatch.h"
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <omp.h>

#include "bench_scenes.h"
#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/compute/hsib_playback.h"
#include "hsi/triangulate.h"

using namespace hsi;

namespace {
using Clock = std::chrono::steady_clock;

// Median of `repeats` runs of fn (ms each).
template <class F>
double median_ms(int repeats, F&& fn) {
  fn();  // warm
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    fn();
    t.push_back(ms_since(t0));
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"GPU playback of .hsib (Vulkan) vs the CPU runtime: N instances of a V-vertex sprite"};
  std::string scene_path = std::string(HSI_ASSETS_DIR) + "/bar_holes.json";
  int vertices = 10000, repeats = 9;
  bool distortion = false;
  std::vector<int> instance_counts{1, 100, 1000};
  app.add_option("--scene", scene_path, "Scene file")->capture_default_str();
  app.add_option("--vertices", vertices, "Sprite mesh size (approximate vertex count)")->capture_default_str();
  app.add_option("--instances", instance_counts, "Instance counts (one table row each)");
  app.add_option("--repeats", repeats, "Timed runs per measurement (the median is shown)")->capture_default_str();
  app.add_flag("--distortion", distortion, "Also compute sigma1, sigma2 per vertex (derivative rows) on both paths");
  CLI11_PARSE(app, argc, argv);

  bench::Loaded L = bench::load(scene_path, 2000, 0.2);
  const ShapeSetup& setup = *L.setup;
  FrameFile ff;
  ff.cage = setup.cage;
  for (size_t k = 0; k < L.maps.size(); ++k) ff.frames.push_back({L.times[k], true, true, true, 0, 2.0, L.maps[k]});
  BakeOptions bo;
  bo.blend_substeps = 0;  // timing only: the blend shown is chosen below
  const std::string bytes = encode_baked(setup.shape, ff, bo);
  hsib_sequence* seq = nullptr;
  char error[256];
  if (hsib_open_memory(bytes.data(), bytes.size(), &seq, error, sizeof error) != HSIB_OK) {
    std::fprintf(stderr, "bench_hsib_gpu: %s\n", error);
    return 1;
  }
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(setup.shape, vertices);
  const TriMesh mesh = triangulate(setup.shape, to);
  std::vector<float> rest;
  for (const cd& v : mesh.vertices) {
    rest.push_back(static_cast<float>(v.real()));
    rest.push_back(static_cast<float>(v.imag()));
  }
  const size_t P = mesh.vertices.size();
  hsib_binding* b = nullptr;
  if (hsib_bind_flags(seq, rest.data(), P, 0, nullptr, distortion ? HSIB_BIND_DERIVATIVES : 0u, &b, error, sizeof error) != HSIB_OK) {
    std::fprintf(stderr, "bench_hsib_gpu: %s\n", error);
    return 1;
  }
  hsib_info info;
  hsib_get_info(seq, &info);
  const hsib_blend blend{0, std::min(1u, info.frame_count - 1), 0.4f, 0};
  const int threads = omp_get_max_threads();

  try {
    compute::ContextOptions co;
    co.want_float64 = false;
    compute::Context ctx(co);
    std::printf("scene %s: sprite of %zu vertices, row length R = %u; device %s (%s); CPU %d threads\n", L.name.c_str(), P,
                info.row_length, ctx.info().name.c_str(), ctx.info().type_name().c_str(), threads);
    std::printf("every instance shows the blend of frames %u and %u at s = %.1f%s; median of %d runs\n\n", blend.frame0, blend.frame1,
                static_cast<double>(blend.s), distortion ? ", positions and sigma1, sigma2" : "", repeats);
    std::printf("| instances | vertices | CPU 1 thread ms | CPU %d threads ms | GPU pass ms (device) | GPU ms (wall: uniforms, submit, wait) "
                "| CPU 1 thread / GPU device | CPU %d threads / GPU device | CPU %d threads / GPU wall | upload per frame CPU path / GPU path |\n",
                threads, threads, threads);
    std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const int n : instance_counts) {
      std::vector<float> out(2 * P * static_cast<size_t>(n)), sigma(distortion ? out.size() : 0);
      const auto instance = [&](int i) {
        hsib_evaluate_blend(b, &blend, out.data() + 2 * P * static_cast<size_t>(i), 0);
        if (distortion) hsib_evaluate_blend_distortion(b, &blend, sigma.data() + 2 * P * static_cast<size_t>(i), 0);
      };
      omp_set_num_threads(1);
      const double cpu1 = median_ms(std::max(1, repeats / 3), [&] {
        for (int i = 0; i < n; ++i) instance(i);
      });
      omp_set_num_threads(threads);
      const double cpuN = median_ms(repeats, [&] {
#pragma omp parallel for schedule(static)
        for (int i = 0; i < n; ++i) instance(i);
      });
      compute::HsibPlayback gpu(ctx, b, static_cast<uint32_t>(n), compute::MemoryUse::kDeviceLocal, distortion);
      std::vector<double> device;
      const double wall = median_ms(repeats, [&] {
        gpu.set_blend(blend);
        device.push_back(gpu.run());
      });
      device.erase(device.begin());  // the warm-up run
      std::sort(device.begin(), device.end());
      const double dev = device[device.size() / 2];
      const double cpu_upload = (distortion ? 16.0 : 8.0) * static_cast<double>(P) * n, gpu_upload = 16.0 * (info.row_length + 2);
      std::printf("| %d | %zu | %.3f | %.3f | %.4f | %.4f | %.2fx | %.2fx | %.2fx | %.0f KB / %.1f KB |\n", n, P * static_cast<size_t>(n), cpu1,
                  cpuN, dev, wall, cpu1 / dev, cpuN / dev, cpuN / wall, cpu_upload / 1024, gpu_upload / 1024);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_hsib_gpu: %s\n", e.what());
    hsib_unbind(b);
    hsib_close(seq);
    return 1;
  }
  hsib_unbind(b);
  hsib_close(seq);
  return 0;
}
