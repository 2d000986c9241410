// Benchmark of the Vulkan dense evaluation (compute/dense_eval.h) against the CPU
// reference (hsi::evaluate_map at the same points) in the same run: grids of 256²,
// 1024², 2048² over a scene's shape, ms per frame and the ratio. Then dense
// certification (compute/dense_certify.h) against the CPU hsi::Certifier on the
// scene's keyframes. Prints the device and Markdown tables. Not a test: timings only.
#include "hsi/stopwatch.h"
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <omp.h>

#include "hsi/certificate.h"
#include "hsi/compute/dense_certify.h"
#include "hsi/compute/diagnostics.h"
#include "hsi/compute/dense_eval.h"
#include "hsi/scene_io.h"
#include "bench_frame.h"
#include "bench_render.h"

using namespace hsi;

namespace {

using Clock = std::chrono::steady_clock;

// The 1-minute load average: timings on a shared machine are only as good as this.
std::string load_average() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  if (!f) return "n/a";
  char buf[64] = {};
  const bool ok = std::fgets(buf, sizeof buf, f) != nullptr;
  std::fclose(f);
  std::string s = ok ? buf : "n/a";
  return s.substr(0, s.find(' '));
}

// The CPU reference at every point, in chunks (a full basis matrix of 4M points
// would not fit in memory). Returns f_z so the caller can compare.
void cpu_evaluate(const Cage& cage, const HarmonicMap& map, const std::vector<cd>& pts, std::vector<cd>& f,
                  std::vector<cd>& f_z) {
  constexpr size_t kChunk = 16384;
  f.resize(pts.size());
  f_z.resize(pts.size());
  for (size_t s = 0; s < pts.size(); s += kChunk) {
    const size_t n = std::min(kChunk, pts.size() - s);
    const BasisRows rows = evaluate_basis(cage, std::span<const cd>(pts.data() + s, n), kBasisC | kBasisD);
    const MapValues v = evaluate_map(rows, map);
    for (size_t i = 0; i < n; ++i) {
      f[s + i] = v.f(static_cast<Eigen::Index>(i));
      f_z[s + i] = v.f_z(static_cast<Eigen::Index>(i));
    }
  }
}

// Dense certification vs the CPU Certifier on each scene's keyframes: median ms per
// map over `frames` runs of every keyframe, both backends in the same run.
void certification_table(const compute::Context& ctx, const std::vector<std::string>& scenes, int frames, int samples) {
  std::printf("\nCertification: the injectivity certificate of each keyframe map (breakpoint values, Lipschitz\n"
              "bounds with adaptive subdivision, argument principle). GPU ms/map: median certify() wall time\n"
              "(upload, both dispatches, readback, reduction); dispatch ms: submit to fence. CPU ms/map: median\n"
              "hsi::Certifier::certify. Agree: identical verdicts and failing segments; bound diff: max difference\n"
              "of sigma1 max and sigma2 min relative to sigma1 max, and of k max.\n\n");
  std::printf("| scene | segments | m + N | maps | certified | GPU ms/map | dispatch ms | CPU ms/map | CPU / GPU | agree | "
              "bound diff |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : scenes) {
    const Scene scene = load_scene(path);
    const Cage cage = scene_cage(scene);
    const BoundarySamples g = sample_boundary(scene.shape, samples > 0 ? samples : scene.samples);
    std::vector<HarmonicMap> maps;
    for (const Keyframe& k : scene.keyframes)
      if (k.coefficients) maps.push_back(*k.coefficients);
    if (maps.empty()) maps.push_back(affine_map(cage, {1.1, 0.2}, {0.1, 0.0}, {0.0, 0.0}));
    const Certifier cpu(scene.shape, cage, g);
    compute::DenseCertifier gpu(ctx, scene.shape, cage, g);
    std::vector<double> gpu_ms, dispatch_ms, cpu_ms;
    int certified = 0, agree = 0;
    double bound_diff = 0;
    for (const HarmonicMap& map : maps) {
      CertificateResult rg = gpu.certify(map), rc;  // warm-up
      for (int i = 0; i < frames; ++i) {
        auto t0 = Clock::now();
        rg = gpu.certify(map);
        gpu_ms.push_back(ms_since(t0));
        dispatch_ms.push_back(gpu.last_stats().gpu_ms);
        t0 = Clock::now();
        rc = cpu.certify(map);
        cpu_ms.push_back(ms_since(t0));
      }
      certified += rg.certified;
      agree += rg.certified == rc.certified && rg.fail_loop == rc.fail_loop && rg.fail_edge == rc.fail_edge;
      if (rc.certified && rg.certified)
        bound_diff = std::max({bound_diff, std::abs(rg.k_max - rc.k_max),
                               std::max(std::abs(rg.sigma1_max - rc.sigma1_max), std::abs(rg.sigma2_min - rc.sigma2_min)) /
                                   rc.sigma1_max});
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    const double tg = median(gpu_ms), tc = median(cpu_ms);
    std::printf("| %s | %d | %d | %zu | %d | %.2f | %.2f | %.2f | %.2f | %d/%zu | %.1e |\n",
                scene.name.empty() ? path.c_str() : scene.name.c_str(), gpu.breakpoint_count(), basis_size(cage),
                maps.size(), certified, tg, median(dispatch_ms), tc, tc / tg, agree, maps.size(), bound_diff);
    std::fflush(stdout);
  }
}

// Where the grid evaluation's time goes: one n × n grid per variant, GPU time by
// timestamps: the frame's pass (mask + evaluation inside), every point evaluated
// without a mask, and the mask alone (the shape moved off the grid, so every point
// runs the outer loop's crossing test and nothing is evaluated).
void eval_breakdown(const compute::Context& ctx, const std::vector<std::string>& scenes, int n) {
  std::printf("\nGrid evaluation breakdown at %d x %d (device ms, median of 5):\n\n"
              "| scene | precision | inside | masked + inside evaluated | all evaluated, no mask | mask only |\n"
              "|---|---|---|---|---|---|\n", n, n);
  for (const std::string& path : scenes) {
    const bench::VulkanScene v = bench::load_vulkan_scene(path, false);
    const compute::Grid grid = compute::Grid::covering(bounding_box(v.scene.shape), n, n);
    Shape away = v.scene.shape;
    const cd shift = 10.0 * (bounding_box(away).hi - bounding_box(away).lo);
    for (int l = 0; l < away.loop_count(); ++l)
      for (cd& z : away.loop(l)) z += shift;
    for (const compute::Precision precision : {compute::Precision::kFloat, compute::Precision::kDouble}) {
      compute::DenseEvalOptions eo;
      eo.precision = precision;
      eo.skip_outside = true;
      eo.max_points_per_pass = std::max<uint32_t>(eo.max_points_per_pass, static_cast<uint32_t>(n * n));
      compute::DenseEvaluator ev(ctx, eo);
      const Shape* masks[3] = {&v.scene.shape, nullptr, &away};
      double t[3];
      for (int k = 0; k < 3; ++k) {
        std::vector<double> ms;
        for (int i = 0; i < 6; ++i) {
          ctx.submit_and_wait([&](VkCommandBuffer cmd) { ev.record_grid(cmd, v.cage, v.map, grid, masks[k]); });
          if (i > 0) ms.push_back(ctx.last_device_ms());
        }
        std::sort(ms.begin(), ms.end());
        t[k] = ms[ms.size() / 2];
      }
      const compute::DenseField f = ev.evaluate_grid(v.cage, v.map, grid, &v.scene.shape);
      size_t inside = 0;
      for (uint8_t b : f.inside) inside += b;
      std::printf("| %s | %s | %.0f%% | %.3f | %.3f | %.3f |\n", v.name.c_str(), ev.double_precision() ? "double" : "float",
                  100.0 * static_cast<double>(inside) / static_cast<double>(f.inside.size()), t[0], t[1], t[2]);
    }
  }
}

// FMA throughput reached by compute work on the context's queue, for comparison with
// the GPU's peak (an H100 SXM: ~67 TFLOP/s float, ~34 double).
void probe_table(const compute::Context& ctx) {
  const VkPhysicalDeviceMemoryProperties& mp = ctx.memory_properties();
  std::printf("\nMemory types (heap: flags):");
  for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
    std::printf(" %u:%u:0x%x", i, mp.memoryTypes[i].heapIndex, mp.memoryTypes[i].propertyFlags);
  std::printf("\nHeaps:");
  for (uint32_t i = 0; i < mp.memoryHeapCount; ++i)
    std::printf(" %u:%.0fMiB:0x%x", i, static_cast<double>(mp.memoryHeaps[i].size) / 1048576.0, mp.memoryHeaps[i].flags);
  for (const compute::MemoryUse use : {compute::MemoryUse::kDeviceLocal, compute::MemoryUse::kUpload, compute::MemoryUse::kReadback}) {
    const compute::Buffer b(ctx, 4096, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, use);
    std::printf("\nMemoryUse %d -> flags 0x%x", static_cast<int>(use), b.memory_flags());
  }
  std::printf("\n");
  std::printf("\nThroughput probe: 8 independent FMA chains per invocation, 256 per workgroup.\n\n"
              "| queue family | precision | workgroups | device ms | GFLOP/s |\n|---|---|---|---|---|\n");
  for (const bool dbl : {false, true}) {
    if (dbl && !ctx.info().float64) continue;
    for (const uint32_t wg : {1024u, 16384u}) {
      const compute::ThroughputProbe p = compute::probe_fma_throughput(ctx, dbl, wg, dbl ? 1024u : 4096u);
      std::printf("| %u | %s | %u | %.3f | %.0f |\n", ctx.info().queue_family, dbl ? "double" : "float", wg,
                  p.device_ms, p.gflops);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi Vulkan dense evaluation benchmark: GPU grid vs CPU evaluate_map, Markdown table"};
  std::vector<std::string> scenes;
  std::vector<int> sizes = {256, 1024, 2048};
  int frames = 3, cpu_frames = 1;
  bool use_float = false, validation = false;
  std::string device;
  app.add_option("scenes", scenes, "Scene files (.json)")->required();
  app.add_option("--sizes", sizes, "Grid sides (n × n points over the shape's bounding box)")->capture_default_str();
  app.add_option("--frames", frames, "GPU frames per size (after one warm-up)")->capture_default_str();
  app.add_option("--cpu-frames", cpu_frames, "CPU frames per size")->capture_default_str();
  app.add_option("--device", device, "Vulkan device name substring (default: best device)");
  app.add_flag("--float", use_float, "Use the float shader (default: double where supported)");
  app.add_flag("--validation", validation, "Enable the validation layer (slower)");
  int certify_frames = 3, certify_samples = 0;
  app.add_option("--certify-frames", certify_frames, "Certifications per keyframe and backend (0: no certification table)")
      ->capture_default_str();
  app.add_option("--certify-samples", certify_samples, "|G| for the certificate (0: the scene's)")->capture_default_str();
  int render_frames = 5;
  app.add_option("--render-frames", render_frames, "Frames per size for the render rows (0: no render table)")
      ->capture_default_str();
  int frame_frames = 5;
  app.add_option("--frame-frames", frame_frames,
                 "Frames per size for the frame rows (evaluate + certify + draw, device timestamps; 0: none)")
      ->capture_default_str();
  int msaa = 4;
  app.add_option("--msaa", msaa, "MSAA samples of the frame rows' drawing")->capture_default_str();
  std::string raster = "both";
  app.add_option("--raster", raster, "Rasterizer of the frame rows: graphics, compute, auto or both")
      ->check(CLI::IsMember({"graphics", "compute", "auto", "both"}))
      ->capture_default_str();
  bool no_boundary = false;
  app.add_flag("--no-boundary", no_boundary, "Frame rows: draw no boundary lines (the textured shape only)");
  int breakdown = 0;
  app.add_option("--eval-breakdown", breakdown, "Also time the grid evaluation's parts at this n (0: no)");
  bool probe = false;
  app.add_flag("--probe", probe, "Also measure the FMA throughput that compute work reaches (float, double)");
  CLI11_PARSE(app, argc, argv);

  compute::ContextOptions co;
  co.validation = validation;
  co.device_name = device;
  std::unique_ptr<compute::Context> ctx;
  try {
    ctx = std::make_unique<compute::Context>(co);
  } catch (const compute::VulkanError& e) {
    std::fprintf(stderr, "bench_vulkan: %s\n", e.what());
    return 2;
  }
  compute::DenseEvalOptions eo;
  eo.precision = use_float ? compute::Precision::kFloat : compute::Precision::kAuto;
  compute::DenseEvaluator eval(*ctx, eo);
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("Vulkan device: %s (%s, Vulkan %u.%u), shader precision: %s\n", ctx->info().name.c_str(),
              ctx->info().type_name().c_str(), VK_API_VERSION_MAJOR(ctx->info().api_version),
              VK_API_VERSION_MINOR(ctx->info().api_version), eval.double_precision() ? "double" : "float");
  std::printf("CPU reference: hsi::evaluate_basis(C, D) + evaluate_map, %d OpenMP threads; LP_NUM_THREADS=%s; "
              "load average %s\n\n",
              omp_get_max_threads(), lp ? lp : "(unset)", load_average().c_str());
  std::printf("GPU ms/frame: median evaluate_grid wall time (upload, dispatch, readback, conversion; inside mask\n"
              "on); dispatch ms: submit to fence. CPU ms/frame: mean. Max error: max |f_gpu - f_cpu| / max |f_cpu|\n"
              "over the grid points inside the shape.\n\n");
  std::printf("| scene | grid | points | m + N | GPU ms/frame | dispatch ms | CPU ms/frame | CPU / GPU | max error |\n"
              "|---|---|---|---|---|---|---|---|---|\n");

  for (const std::string& path : scenes) {
    const bench::VulkanScene v = bench::load_vulkan_scene(path, false);
    const Scene& scene = v.scene;
    const Cage& cage = v.cage;
    const HarmonicMap& map = v.map;
    const std::string& name = v.name;
    for (int n : sizes) {
      const compute::Grid grid = compute::Grid::covering(bounding_box(scene.shape), n, n);
      compute::DenseField field = eval.evaluate_grid(cage, map, grid, &scene.shape);  // warm-up
      std::vector<double> wall, dispatch_ms;
      for (int i = 0; i < std::max(frames, 1); ++i) {
        const auto t0 = Clock::now();
        field = eval.evaluate_grid(cage, map, grid, &scene.shape);
        wall.push_back(ms_since(t0));
        dispatch_ms.push_back(eval.last_stats().gpu_ms);
      }
      std::sort(wall.begin(), wall.end());
      std::sort(dispatch_ms.begin(), dispatch_ms.end());
      const double gpu = wall[wall.size() / 2], dispatch = dispatch_ms[dispatch_ms.size() / 2];

      const std::vector<cd> pts = grid.points();
      std::vector<cd> f, f_z;
      double cpu = 0;
      for (int i = 0; i < cpu_frames; ++i) {
        const auto t0 = Clock::now();
        cpu_evaluate(cage, map, pts, f, f_z);
        cpu += ms_since(t0);
      }
      cpu /= std::max(cpu_frames, 1);
      double err = 0, mag = 0;
      for (size_t k = 0; k < pts.size(); ++k) {
        if (!field.inside[k]) continue;  // outside the shape values near the cage are huge and meaningless
        err = std::max(err, std::abs(field.f[k] - f[k]));
        mag = std::max(mag, std::abs(f[k]));
      }
      std::printf("| %s | %d² | %zu | %d | %.1f | %.1f | %.1f | %.2f | %.1e |\n", name.c_str(), n, pts.size(),
                  basis_size(cage), gpu, dispatch, cpu, cpu / gpu, err / std::max(mag, 1e-300));
      std::fflush(stdout);
    }
  }
  if (certify_frames > 0 && !ctx->info().float64)
    std::printf("\nCertification: skipped, %s has no shaderFloat64 (the dense certificate is double only)\n",
                ctx->info().name.c_str());
  else if (certify_frames > 0)
    certification_table(*ctx, scenes, certify_frames, certify_samples);
  if (render_frames > 0) bench::render_table(*ctx, scenes, sizes, render_frames, use_float);
  if (frame_frames > 0) {
    std::vector<compute::Rasterizer> rasterizers;
    if (raster == "graphics" || raster == "both") rasterizers.push_back(compute::Rasterizer::kGraphics);
    if (raster == "compute" || raster == "both") rasterizers.push_back(compute::Rasterizer::kCompute);
    if (raster == "auto") rasterizers.push_back(compute::Rasterizer::kAuto);
    bench::frame_table(*ctx, scenes, sizes, frame_frames, msaa, rasterizers, !no_boundary);
  }
  if (probe) probe_table(*ctx);
  if (breakdown > 0) eval_breakdown(*ctx, scenes, breakdown);
  std::printf("\nload average at the end: %s\n", load_average().c_str());
  if (validation && ctx->validation_log()->count()) {
    std::fprintf(stderr, "%s\n", ctx->validation_log()->summary().c_str());
    return 1;
  }
  return 0;
}
