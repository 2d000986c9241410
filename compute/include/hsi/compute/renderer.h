// Offscreen rendering of a deformed shape (Vulkan, headless; lavapipe where there
// is no GPU). The shape's triangulation (hsi::triangulate) is drawn at f(rest vertex)
// with its own texture (texture coordinates = rest positions in the texture's
// rectangle), so the outline and every hole clip exactly where the map sends them;
// optional overlays: the conformal-distortion colour map, the boundary as lines,
// handles as discs; an uncertified frame gets a red tint and a red border. 4× MSAA,
// resolved, read back as an RGBA image. The triangles are rasterized by the graphics
// pipeline or by compute shaders (Rasterizer), to the same picture.
//
// One command buffer per frame: the dense evaluation (DenseEvaluator::record_points)
// computes f and the distortion at the mesh vertices and handles on the GPU, and the
// vertex shaders read them from its output buffer: nothing goes through the host
// between evaluating and drawing. Geometry from elsewhere (a mesh-based method's
// vertex positions, hsi compare's baselines) goes through the same pipelines: the
// host writes positions and distortion into buffers of the evaluation's layout.
// Text (legends, labels) is the caller's job (the hsi tool composites it with
// cairo); colormap() gives the colours for a legend.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "hsi/compute/dense_eval.h"
#include "hsi/png.h"
#include "hsi/texture_filter.h"
#include "hsi/triangulate.h"

namespace hsi::compute {

// Overlay bits, combinable.
enum Overlay : uint32_t {
  kOverlayNone = 0,
  kOverlayDistortion = 1u,  // conformal distortion σ1/σ2 as a colour map over the texture
  kOverlayBoundary = 2u,    // the image of the shape's outline and holes, as lines
  kOverlayHandles = 4u,     // the handles, as discs at f(handle)
};

// The colour map of the distortion overlay at t in [0, 1] (clamped): viridis, as
// the shaders compute it. RGB in [0, 1].
std::array<double, 3> colormap(double t);

// World (the shape's plane, y up) to pixels (x right, y down from the image's
// top-left corner): a uniform scale about a centre.
struct View {
  cd world_center{0, 0};
  double pixels_per_unit = 1;
  cd pixel_center{0, 0};

  cd to_pixel(cd w) const {
    return {pixel_center.real() + pixels_per_unit * (w.real() - world_center.real()),
            pixel_center.imag() - pixels_per_unit * (w.imag() - world_center.imag())};
  }
  // The largest view showing `world` in a width × height image with `margin_px` on
  // every side and `bottom_px` more kept free at the bottom (e.g. for a legend),
  // centred in what remains. Throws InputError for an empty box or no room.
  static View fit(const BoundingBox& world, int width, int height, double margin_px = 0, double bottom_px = 0);
};

struct RenderStyle {
  uint32_t overlays = kOverlayNone;
  std::array<float, 4> background{1, 1, 1, 1};  // straight RGBA in [0, 1]; alpha 0 for a transparent image
  std::array<float, 4> fill{0.78f, 0.84f, 0.92f, 1};  // the shape's colour when no texture is set
  // Distortion colour map: t = (κ − lo) / (hi − lo), κ = σ1/σ2 ≥ 1 (folds saturate).
  double distortion_lo = 1, distortion_hi = 2;
  float distortion_opacity = 0.85f;  // over the texture
  std::array<float, 4> boundary_color{0.05f, 0.07f, 0.12f, 1};
  float boundary_width_px = 2;
  std::array<float, 4> handle_color{1.0f, 0.62f, 0.1f, 1}, handle_outline{0.08f, 0.08f, 0.1f, 1};
  float handle_radius_px = 6, handle_outline_px = 1.5f;
  // The frame could not be certified: the shape is tinted red and the image gets a
  // red border of border_px pixels (≤ 0: max(4, min(width, height) / 64)).
  bool uncertified = false;
  float border_px = 0;
};

// A round upper end for the distortion colour map over [1, hi']: 1 + 4 steps of a
// round size (1, 2, 2.5 or 5 × 10^k) that reach hi, so that a legend's five ticks read
// as round numbers (hsi render, hsi compare, the viewer).
double round_distortion_hi(double hi);

// The mesh with every triangle's corners made vertices of their own (3 per triangle,
// in triangle order: vertex 3t + k is corner k of triangle t), boundary edges and
// loops carried over: drawing it through Renderer::render(positions, kappa, ...)
// with the same value at a triangle's three corners shows per-triangle quantities
// flat (a mesh-based method's per-triangle distortion) instead of smeared across
// neighbours. `source[v]` is the original vertex of vertex v.
struct UnweldedMesh {
  TriMesh mesh;
  std::vector<int> source;
};
UnweldedMesh unweld(const TriMesh& mesh);

// How the shape's triangles become pixels. Both give the same picture (the tests
// hold them to the golden images' tolerance): the same sample locations, one shading
// per pixel and triangle at the pixel's centre, the same colours, blended over the
// background and averaged. Lines and handle discs are drawn by the graphics pipeline
// either way (on top of the resolved image in the compute path: their edges are
// anti-aliased by analytic coverage). Where the image of the shape overlaps itself (a
// map that is not globally injective, issue #20), both show the top layer alone, over
// the background, whatever its alpha: per sample the last triangle in the mesh's
// triangle order that covers it (the compute path's visibility buffer keeps the
// largest 1 + triangle id by atomicMax; the graphics path draws the mesh without
// blending, so Vulkan's primitive order leaves the last triangle's colour, composited
// over the background in the fragment shader). Deterministic, and the same in both.
enum class Rasterizer {
  kAuto,      // kCompute, except on CPU devices (lavapipe, whose rasterizer is faster
              // there) or where the visibility buffer would not fit (see kCompute).
              // Measured on an H100 only: 5-9x faster from 1024² up, close at 256²
  kGraphics,  // the graphics pipeline: the mesh drawn into an MSAA image, resolved
  kCompute,   // compute shaders (shaders/raster*.comp): a visibility buffer of
              // width × height × samples triangle ids (4 bytes each; must fit in one
              // storage buffer, else VulkanError), then a shading and resolve pass.
              // On compute GPUs whose drawing runs on a few units (the H100 draws on 2
              // of 66 TPCs) it is several times faster.
};

struct RendererOptions {
  int msaa_samples = 4;  // 1, 2, 4 or 8; the graphics path lowers it to what the device supports
  Rasterizer rasterizer = Rasterizer::kAuto;
  DenseEvalOptions evaluation;  // precision of the positions (double where the device has it)
};

// Host wall-clock times of the last render() call, in milliseconds.
struct RenderStats {
  double upload_ms = 0;    // recording, uploading the map and the points
  double gpu_ms = 0;       // submit to fence: evaluation, drawing, resolve (render(): and the copy to host memory)
  double readback_ms = 0;  // render(): un-premultiplying into the RgbaImage
};

class Renderer {
 public:
  // Throws VulkanUnavailable if the context's queue cannot draw, InputError for a bad size.
  Renderer(const Context& context, int width, int height, const RendererOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  int msaa_samples() const { return samples_; }
  Rasterizer rasterizer() const { return rasterizer_; }  // kGraphics or kCompute, as chosen
  bool double_precision() const { return eval_.double_precision(); }

  // The rest mesh and the handles (rest positions), fixed for a scene. Throws
  // InputError for an empty mesh or an index out of range.
  void set_mesh(const TriMesh& mesh, std::span<const cd> handles = {});
  // The texture (straight alpha) and the world rectangle [x0, y0, x1, y1] it covers:
  // (x0, y1) is its top-left pixel corner. Mipmapped, sampled bilinearly (trilinear
  // across levels) or, with TextureFilter::Nearest, the nearest texel of the nearest
  // level (pixel art stays crisp), by both rasterizers. An empty image removes the
  // texture (the shape is then filled with RenderStyle::fill).
  void set_texture(const RgbaImage& texture, const std::array<double, 4>& rect,
                   TextureFilter filter = TextureFilter::Linear);
  bool has_texture() const { return has_texture_; }
  TextureFilter texture_filter() const { return filter_; }

  // One frame: f = map over `cage` (m + N coefficients each, else InputError).
  RgbaImage render(const Cage& cage, const HarmonicMap& map, const View& view, const RenderStyle& style);
  // The same frame left on the device (in the resolved image), nothing copied out:
  // what a consumer that keeps frames on the GPU pays (and what the benchmark times).
  void draw(const Cage& cage, const HarmonicMap& map, const View& view, const RenderStyle& style);
  // draw() recorded into the caller's command buffer (e.g. one submission per frame
  // with the dense evaluation and the certificate): the mesh evaluation, its
  // barriers and the render pass. The caller submits `cmd` and waits for it before
  // the next record/draw/render. With mark_evaluation, a Context::mark follows the
  // mesh evaluation (to time the two parts).
  void record(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, const View& view, const RenderStyle& style,
              bool mark_evaluation = false);
  // The last frame drawn (draw, record after its submission finished, or render),
  // copied to the host as render() returns it. InputError before any frame.
  RgbaImage read_frame();

  // One frame from given geometry instead of a map: vertex i of the mesh (set_mesh)
  // at positions[i], its conformal distortion σ1/σ2 (for the overlay; ≤ 0, infinite
  // or NaN marks a fold and saturates the colour map) kappa[i], both one per mesh
  // vertex (else InputError; positions must be finite). Handles are drawn at
  // handle_positions, one per handle of set_mesh, or not at all when it is empty.
  // Same texture, overlays, MSAA, view and style as the map path: the values are
  // written to buffers of the dense evaluation's layout that the same shaders read.
  RgbaImage render(std::span<const cd> positions, std::span<const double> kappa, const View& view,
                   const RenderStyle& style, std::span<const cd> handle_positions = {});
  void draw(std::span<const cd> positions, std::span<const double> kappa, const View& view, const RenderStyle& style,
            std::span<const cd> handle_positions = {});
  const RenderStats& last_stats() const { return stats_; }

 private:
  struct Impl;  // the GPU state (src/renderer_impl.h)
  void upload_uv();
  // Writes positions and distortion into the given-geometry buffers; returns how many
  // handles to draw.
  size_t upload_given(std::span<const cd> positions, std::span<const double> kappa, std::span<const cd> handle_positions);
  // cage == nullptr: draw the given-geometry buffers (upload_given) with `handles` discs.
  void frame(const Cage* cage, const HarmonicMap* map, size_t handles, const View& view, const RenderStyle& style,
             bool copy_out);
  void check_frame(const View& view, const RenderStyle& style) const;
  void record_frame(VkCommandBuffer cmd, const Cage* cage, const HarmonicMap* map, size_t handles, const View& view,
                    const RenderStyle& style, bool copy_out, bool mark_evaluation);
  RgbaImage read_image();
  void record_copy_out(VkCommandBuffer cmd);

  const Context* context_;
  int width_, height_, samples_ = 1;
  Rasterizer rasterizer_ = Rasterizer::kGraphics;
  DenseEvaluator eval_;
  std::vector<cd> points_;  // mesh vertices, then handles
  std::vector<cd> rest_vertices_;
  size_t vertex_count_ = 0, handle_count_ = 0, index_count_ = 0, segment_count_ = 0;
  std::array<double, 4> texture_rect_{0, 0, 1, 1};
  bool has_texture_ = false, uv_dirty_ = true, drawn_ = false;
  TextureFilter filter_ = TextureFilter::Linear;
  RenderStats stats_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hsi::compute
