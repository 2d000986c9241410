// Render rows of bench_vulkan: per frame, the dense evaluation of an n × n grid over
// the shape and the offscreen rendering of the frame at n × n pixels (the mesh
// evaluated at f on the GPU and drawn textured with the boundary, 4× MSAA), against
// the CPU evaluation of the same mesh vertices in the same run.
#pragma once

#include "hsi/stopwatch.h"
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "hsi/basis.h"
#include "hsi/compute/dense_eval.h"
#include "hsi/compute/renderer.h"
#include "hsi/scene_io.h"
#include "hsi/triangulate.h"

namespace hsi::bench {

// f and f_z at the points on the CPU (the reference), in chunks so memory stays bounded.
inline void cpu_mesh_eval(const Cage& cage, const HarmonicMap& map, const std::vector<cd>& pts, std::vector<cd>& f) {
  constexpr size_t kChunk = 16384;
  f.resize(pts.size());
  for (size_t s = 0; s < pts.size(); s += kChunk) {
    const size_t n = std::min(kChunk, pts.size() - s);
    const BasisRows rows = evaluate_basis(cage, std::span<const cd>(pts.data() + s, n), kBasisC | kBasisD);
    const MapValues v = evaluate_map(rows, map);
    for (size_t i = 0; i < n; ++i) f[s + i] = v.f(static_cast<Eigen::Index>(i));
  }
}

// A scene as the Vulkan benchmarks draw it: its cage, the last keyframe given by
// coefficients (an affine map when none is), and its texture with the rectangle it
// covers (the shape's bounding box unless the scene says otherwise; not read when
// `with_texture` is false).
struct VulkanScene {
  std::string name;
  Scene scene;
  Cage cage;
  HarmonicMap map;
  RgbaImage texture;
  std::array<double, 4> rect{0, 0, 1, 1};
};

inline VulkanScene load_vulkan_scene(const std::string& path, bool with_texture = true) {
  VulkanScene v;
  v.scene = load_scene(path);
  v.name = v.scene.name.empty() ? path : v.scene.name;
  v.cage = scene_cage(v.scene);
  v.map = affine_map(v.cage, {1.1, 0.2}, {0.1, 0.0}, {0.0, 0.0});
  for (const Keyframe& k : v.scene.keyframes)
    if (k.coefficients) v.map = *k.coefficients;
  if (with_texture && !v.scene.texture.empty()) {
    v.texture = read_png(v.scene.texture_path());
    v.rect = v.scene.texture_rect_or_bounds();
  }
  return v;
}

// The render mesh for an n × n image (about n²/50 vertices, as hsi render uses).
inline TriMesh render_mesh(const Shape& shape, int n) {
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(shape, std::max(2000, n * n / 50));
  return triangulate(shape, to);
}

// The view that frames the mesh's image under the map in an n × n image.
inline compute::View frame_view(const VulkanScene& v, const TriMesh& mesh, int n) {
  std::vector<cd> f;
  cpu_mesh_eval(v.cage, v.map, mesh.vertices, f);
  BoundingBox box{f[0], f[0]};
  for (const cd& z : f) {
    box.lo = {std::min(box.lo.real(), z.real()), std::min(box.lo.imag(), z.imag())};
    box.hi = {std::max(box.hi.real(), z.real()), std::max(box.hi.imag(), z.imag())};
  }
  return compute::View::fit(box, n, n, 0.04 * n);
}

inline void render_table(const compute::Context& ctx, const std::vector<std::string>& scenes, const std::vector<int>& sizes,
                         int frames, bool use_float) {
  using Clock = std::chrono::steady_clock;
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::printf("\nRendering: per frame at n × n pixels, the render mesh (about n²/50 vertices, as hsi render uses)\n"
              "evaluated at f on the GPU and drawn with its texture and boundary, 4x MSAA. grid eval: median\n"
              "evaluate_grid wall time of the n² grid (with readback). draw: median Renderer::draw wall time (evaluate\n"
              "the mesh + draw + resolve, the frame stays on the device); render: Renderer::render (plus the copy to\n"
              "host memory and conversion to RGBA). grid eval + draw: the sum, per frame. CPU mesh eval: the CPU\n"
              "reference evaluate_map at the same mesh vertices, mean; CPU / draw: its ratio to the draw.\n\n");
  std::printf("| scene | image | mesh vertices | grid eval ms | draw ms | render ms | readback ms | grid eval + draw ms | "
              "CPU mesh eval ms | CPU / draw |\n|---|---|---|---|---|---|---|---|---|---|\n");
  compute::RendererOptions ro;
  ro.evaluation.precision = use_float ? compute::Precision::kFloat : compute::Precision::kAuto;
  compute::DenseEvalOptions eo = ro.evaluation;
  eo.skip_outside = true;
  compute::DenseEvaluator grid_eval(ctx, eo);
  for (const std::string& path : scenes) {
    const VulkanScene v = load_vulkan_scene(path);
    const Scene& scene = v.scene;
    const Cage& cage = v.cage;
    const HarmonicMap& map = v.map;
    for (int n : sizes) {
      const TriMesh mesh = render_mesh(scene.shape, n);
      compute::Renderer renderer(ctx, n, n, ro);
      renderer.set_mesh(mesh, scene.handles);
      renderer.set_texture(v.texture, v.rect);
      const compute::View view = frame_view(v, mesh, n);
      compute::RenderStyle style;
      style.overlays = compute::kOverlayBoundary;
      const compute::Grid grid = compute::Grid::covering(bounding_box(scene.shape), n, n);

      grid_eval.evaluate_grid(cage, map, grid, &scene.shape);  // warm-ups
      renderer.draw(cage, map, view, style);
      renderer.render(cage, map, view, style);
      std::vector<double> grid_ms, draw_ms, render_ms, readback_ms, pair_ms;
      for (int i = 0; i < std::max(frames, 1); ++i) {
        auto t0 = Clock::now();
        grid_eval.evaluate_grid(cage, map, grid, &scene.shape);
        const double g = ms_since(t0);
        t0 = Clock::now();
        renderer.draw(cage, map, view, style);
        const double d = ms_since(t0);
        t0 = Clock::now();
        renderer.render(cage, map, view, style);
        render_ms.push_back(ms_since(t0));
        readback_ms.push_back(renderer.last_stats().readback_ms);
        grid_ms.push_back(g);
        draw_ms.push_back(d);
        pair_ms.push_back(g + d);
      }
      std::vector<cd> f;
      const auto t_cpu = Clock::now();
      cpu_mesh_eval(cage, map, mesh.vertices, f);
      const double cpu = ms_since(t_cpu);
      const double draw = median(draw_ms);
      std::printf("| %s | %d² | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f |\n", v.name.c_str(), n,
                  mesh.vertex_count(), median(grid_ms), draw, median(render_ms), median(readback_ms), median(pair_ms),
                  cpu, cpu / draw);
      std::fflush(stdout);
    }
  }
}

}  // namespace hsi::bench
