// Frame rows of bench_vulkan: what one displayed frame costs on the GPU when the
// dense distortion field, the certificate and the picture are all made there, in one
// submission:
//   the n × n grid evaluation over the shape (masked, results left on the device:
//   DenseEvaluator::record_grid) | the dense certificate (DenseCertifier::record) |
//   the render mesh evaluated at f | the render pass at n × n pixels (textured,
//   boundary, 4× MSAA; Renderer::record), the frame staying on the device.
// Device times come from timestamp queries (Context::mark between the parts), so they
// are what the GPU spent, apart from the host's recording, submission and wake-up
// that the wall column adds. Both precisions of the evaluation shader are measured
// (the certificate is always double: its bounds need it).
#pragma once

#include "hsi/stopwatch.h"
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_render.h"
#include "hsi/compute/dense_certify.h"
#include "hsi/compute/diagnostics.h"
#include "hsi/samples.h"

namespace hsi::bench {

inline void frame_table(const compute::Context& ctx, const std::vector<std::string>& scenes, const std::vector<int>& sizes,
                        int frames, int msaa, const std::vector<compute::Rasterizer>& rasterizers, bool boundary = true) {
  using Clock = std::chrono::steady_clock;
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  if (!ctx.info().float64) {
    std::printf("\nFrames: skipped, %s has no shaderFloat64 (the dense certificate is double only)\n",
                ctx.info().name.c_str());
    return;
  }
  if (ctx.info().timestamp_valid_bits == 0) std::printf("\nFrames: %s has no timestamps; device columns are -1\n", ctx.info().name.c_str());
  std::printf("\nFrames: one submission per frame: evaluate an n x n grid over the shape (f, f_z, f_zbar,\n"
              "distortion; masked, on the device) | certify (double, the scene's samples) | evaluate the render\n"
              "mesh (~n^2/50 vertices) | draw the frame at n x n pixels (textured, %s, %dx MSAA). Medians over\n"
              "the frames of the GPU time of each part (timestamps between them) and of the whole submission\n"
              "(frame dev), after 2 s of saturating FMA work (GPUs) and 1 s of warm-up frames per row; frame\n"
              "wall: host time, recording, submission and wait included. precision: of the evaluation shaders\n"
              "(grid and mesh). raster: how the frame's triangles became pixels (renderer.h: graphics pipeline,\n"
              "or compute shaders with a visibility buffer). pieces: certificate pieces per segment (1: no\n"
              "subdivision).\n\n", boundary ? "boundary" : "no overlays", msaa);
  // Raise the clocks first: the frames alone keep an H100 only about half busy (the
  // host waits for each), and after the CPU tables before them its clocks start from
  // idle; 1 s of frames then left the first rows up to 2.3× slow. (Not on a CPU
  // device, which has no such clocks and would take minutes.)
  if (!ctx.info().is_cpu())
    for (const auto until = Clock::now() + std::chrono::milliseconds(2000); Clock::now() < until;)
      compute::probe_fma_throughput(ctx, false, 65536, 4096);
  std::printf("| scene | n | precision | raster | segments | pieces | eval ms | certify ms | mesh ms | draw ms | "
              "frame dev ms | frame wall ms | certified |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : scenes) {
    const VulkanScene v = load_vulkan_scene(path);
    const Scene& scene = v.scene;
    const Cage& cage = v.cage;
    const HarmonicMap& map = v.map;
    compute::DenseCertifier certifier(ctx, scene.shape, cage, sample_boundary(scene.shape, scene.samples));
    for (int n : sizes) {
      const TriMesh mesh = render_mesh(scene.shape, n);
      const compute::View view = frame_view(v, mesh, n);
      for (const compute::Precision precision : {compute::Precision::kFloat, compute::Precision::kDouble})
      for (const compute::Rasterizer rasterizer : rasterizers) {
        compute::DenseEvalOptions eo;
        eo.precision = precision;
        eo.skip_outside = true;
        eo.max_points_per_pass = std::max<uint32_t>(eo.max_points_per_pass, static_cast<uint32_t>(n) * static_cast<uint32_t>(n));
        compute::DenseEvaluator grid_eval(ctx, eo);
        compute::RendererOptions ro;
        ro.evaluation.precision = precision;
        ro.msaa_samples = msaa;
        ro.rasterizer = rasterizer;
        compute::Renderer renderer(ctx, n, n, ro);
        renderer.set_mesh(mesh, scene.handles);
        renderer.set_texture(v.texture, v.rect);
        compute::RenderStyle style;
        style.overlays = boundary ? compute::kOverlayBoundary : compute::kOverlayNone;
        const compute::Grid grid = compute::Grid::covering(bounding_box(scene.shape), n, n);
        std::vector<double> parts[4], frame_dev, wall;
        bool certified = true;
        double pieces = 0;
        // i < 0: warm-up, at least 1 s of frames: a GPU idle during the host's work
        // before (the CPU reference of the other tables) runs at a low clock until its
        // power management sees sustained load (on the H100, ~5.7x slower).
        const auto warm_until = Clock::now() + std::chrono::milliseconds(1000);
        for (int i = -1; i < std::max(frames, 1); ++i) {
          if (i == -1 && Clock::now() < warm_until) i = -2;
          const auto t0 = Clock::now();
          ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            grid_eval.record_grid(cmd, cage, map, grid, &scene.shape);
            ctx.mark(cmd);
            certifier.record(cmd, map);
            ctx.mark(cmd);
            renderer.record(cmd, cage, map, view, style, true);
          });
          const CertificateResult cr = certifier.collect();
          const double w = ms_since(t0);
          certified = cr.certified && certified;
          if (i < 0) continue;
          const std::vector<double>& marks = ctx.last_device_marks();
          const double total = ctx.last_device_ms();
          if (marks.size() == 3) {
            const double at[5] = {0, marks[0], marks[1], marks[2], total};
            for (int k = 0; k < 4; ++k) parts[k].push_back(at[k + 1] - at[k]);
          }
          frame_dev.push_back(total);
          wall.push_back(w);
          long n_pieces = 0;
          for (const SegmentCertificate& sc : certifier.last_segments()) n_pieces += sc.pieces;
          pieces = static_cast<double>(n_pieces) / std::max(certifier.breakpoint_count(), 1);
        }
        auto part = [&](int k) { return parts[k].empty() ? -1.0 : median(parts[k]); };
        std::printf("| %s | %d | %s | %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %s |\n", v.name.c_str(),
                    n, grid_eval.double_precision() ? "double" : "float",
                    renderer.rasterizer() == compute::Rasterizer::kCompute ? "compute" : "graphics",
                    certifier.breakpoint_count(), pieces, part(0),
                    part(1), part(2), part(3), median(frame_dev), median(wall), certified ? "yes" : "no");
        std::fflush(stdout);
      }
    }
  }
}

}  // namespace hsi::bench
