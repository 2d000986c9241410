// Frame rows of bench_vulkan: what one displayed frame costs on the GPU when the
// dense distortion field, the certificate and the picture are all made there:
//   submission 1: the n × n grid evaluation over the shape (masked, results left on
//                 the device: DenseEvaluator::record_grid) and the dense certificate
//                 (DenseCertifier::record), one command buffer;
//   submission 2: Renderer::draw at n × n pixels (mesh evaluated at f, textured,
//                 boundary, 4× MSAA, the frame stays on the device).
// Device times come from timestamp queries (Context::last_device_ms), so they are
// what the GPU spent, apart from the host's recording, submission and wake-up that
// the wall columns add. Both precisions of the evaluation shader are measured (the
// certificate is always double: its bounds need it).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_render.h"
#include "hsi/compute/dense_certify.h"
#include "hsi/samples.h"

namespace hsi::bench {

inline void frame_table(const vk::Context& ctx, const std::vector<std::string>& scenes, const std::vector<int>& sizes,
                        int frames) {
  using Clock = std::chrono::steady_clock;
  auto ms_since = [](Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); };
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
  std::printf("\nFrames: evaluate an n x n grid over the shape (f, f_z, f_zbar, distortion; masked, on the device) +\n"
              "certify (double, the scene's samples) + draw the frame at n x n pixels (mesh of ~n^2/50 vertices\n"
              "evaluated on the GPU, textured, boundary, 4x MSAA). Medians over the frames. eval+cert dev / draw\n"
              "dev: GPU time by timestamps of the two submissions; frame dev: their sum; frame wall: host time of\n"
              "both submissions, waits included. precision: of the evaluation shader (grid and mesh).\n\n");
  std::printf("| scene | n | precision | segments | eval+cert dev ms | draw dev ms | frame dev ms | frame wall ms | "
              "certified |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : scenes) {
    const VulkanScene v = load_vulkan_scene(path);
    const Scene& scene = v.scene;
    const Cage& cage = v.cage;
    const HarmonicMap& map = v.map;
    vk::DenseCertifier certifier(ctx, scene.shape, cage, sample_boundary(scene.shape, scene.samples));
    for (int n : sizes) {
      const TriMesh mesh = render_mesh(scene.shape, n);
      const vk::View view = frame_view(v, mesh, n);
      for (const vk::Precision precision : {vk::Precision::kFloat, vk::Precision::kDouble}) {
        vk::DenseEvalOptions eo;
        eo.precision = precision;
        eo.skip_outside = true;
        eo.max_points_per_pass = std::max<uint32_t>(eo.max_points_per_pass, static_cast<uint32_t>(n) * static_cast<uint32_t>(n));
        vk::DenseEvaluator grid_eval(ctx, eo);
        vk::RendererOptions ro;
        ro.evaluation.precision = precision;
        vk::Renderer renderer(ctx, n, n, ro);
        renderer.set_mesh(mesh, scene.handles);
        renderer.set_texture(v.texture, v.rect);
        vk::RenderStyle style;
        style.overlays = vk::kOverlayBoundary;
        const vk::Grid grid = vk::Grid::covering(bounding_box(scene.shape), n, n);
        std::vector<double> ec_dev, draw_dev, frame_dev, wall;
        bool certified = true;
        for (int i = -1; i < std::max(frames, 1); ++i) {  // i = -1: warm-up
          const auto t0 = Clock::now();
          ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            grid_eval.record_grid(cmd, cage, map, grid, &scene.shape);
            certifier.record(cmd, map);
          });
          const double ec = ctx.last_device_ms();
          certified = certifier.collect().certified && certified;
          renderer.draw(cage, map, view, style);
          const double dr = ctx.last_device_ms();
          const double w = ms_since(t0);
          if (i < 0) continue;
          ec_dev.push_back(ec);
          draw_dev.push_back(dr);
          frame_dev.push_back(ec + dr);
          wall.push_back(w);
        }
        std::printf("| %s | %d | %s | %d | %.3f | %.3f | %.3f | %.2f | %s |\n", v.name.c_str(), n,
                    grid_eval.double_precision() ? "double" : "float", certifier.breakpoint_count(), median(ec_dev),
                    median(draw_dev), median(frame_dev), median(wall), certified ? "yes" : "no");
        std::fflush(stdout);
      }
    }
  }
}

}  // namespace hsi::bench
