// hsi_sequence_render: the C API's rendering through the Vulkan offscreen renderer
// (compute/), built only where Vulkan is. One context and renderer per sequence,
// made on the first call and kept for the next ones.
#include <cstdlib>
#include <cstring>

#include "c_api_internal.h"
#include "hsi/compute/renderer.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/triangulate.h"

namespace hsi::capi {
namespace {

struct RenderCache {
  std::unique_ptr<compute::Context> context;
  std::unique_ptr<compute::Renderer> renderer;
  int width = 0, height = 0, msaa = 0;
  double mesh_vertices = 0;
  std::optional<BoundingBox> frames_box;  // every frame's image, for a shared view
};

// The box holding every frame's image of the shape's boundary vertices.
BoundingBox frames_box(const SceneSequence& seq, const TriMesh& mesh) {
  std::vector<cd> boundary;
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.boundary_loop[static_cast<size_t>(v)] >= 0) boundary.push_back(mesh.vertices[static_cast<size_t>(v)]);
  const BasisRows rows = evaluate_basis(seq.setup->cage, boundary, kBasisC);
  BoundingBox bb{cd(1e300, 1e300), cd(-1e300, -1e300)};
  for (const FrameResult& f : seq.frames) {
    const VectorXcd p = evaluate_map(rows, f.map).f;
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      bb.lo = cd(std::min(bb.lo.real(), p(i).real()), std::min(bb.lo.imag(), p(i).imag()));
      bb.hi = cd(std::max(bb.hi.real(), p(i).real()), std::max(bb.hi.imag(), p(i).imag()));
    }
  }
  return bb;
}

}  // namespace

bool render_available(std::string* why) {
  try {
    compute::Context context;
    return true;
  } catch (const std::exception& e) {
    if (why) *why = std::string("no Vulkan device: ") + e.what();
    return false;
  }
}

void render_frame(hsi_sequence& s, uint32_t frame, const hsi_render_options& o, uint8_t* rgba, size_t row_stride) {
  auto cache = std::static_pointer_cast<RenderCache>(s.render_cache);
  if (!cache) {
    cache = std::make_shared<RenderCache>();
    s.render_cache = cache;
  }
  try {
    // HSI_VULKAN_VALIDATION=1: the validation layer on, and any message it reports fails the call.
    const bool validate = std::getenv("HSI_VULKAN_VALIDATION") && std::string(std::getenv("HSI_VULKAN_VALIDATION")) != "0";
    if (!cache->context) {
      compute::ContextOptions co;
      co.validation = validate;
      cache->context = std::make_unique<compute::Context>(co);
    }
    const int w = static_cast<int>(o.width), h = static_cast<int>(o.height);
    const int msaa = o.msaa_samples ? static_cast<int>(o.msaa_samples) : 4;
    if (!cache->renderer || cache->width != w || cache->height != h || cache->msaa != msaa || cache->mesh_vertices != o.mesh_vertices) {
      cache->renderer.reset();
      compute::RendererOptions ro;
      ro.msaa_samples = msaa;
      cache->renderer = std::make_unique<compute::Renderer>(*cache->context, w, h, ro);
      const Scene& scene = *s.scene;
      TriangulateOptions to;
      to.max_edge = edge_for_vertex_count(scene.shape, std::max(16, static_cast<int>(o.mesh_vertices > 0 ? o.mesh_vertices : 4000)));
      const TriMesh mesh = triangulate(scene.shape, to);
      cache->renderer->set_mesh(mesh, scene.handles);
      if (!scene.texture.empty()) {
        cache->renderer->set_texture(read_png(scene.texture_path()), scene.texture_rect_or_bounds(), scene.texture_filter);
      }
      cache->frames_box = frames_box(s.seq, mesh);
      cache->width = w;
      cache->height = h;
      cache->msaa = msaa;
      cache->mesh_vertices = o.mesh_vertices;
    }
    const bool custom_view = o.view[0] != 0 || o.view[1] != 0 || o.view[2] != 0 || o.view[3] != 0;
    if (custom_view && !(o.view[2] > o.view[0] && o.view[3] > o.view[1]))
      throw ApiError{HSI_ERROR_INVALID_ARGUMENT, "hsi_sequence_render: view must be x0 < x1 and y0 < y1"};
    const BoundingBox box = custom_view ? BoundingBox{cd(o.view[0], o.view[1]), cd(o.view[2], o.view[3])} : *cache->frames_box;
    const compute::View view = compute::View::fit(box, w, h, 0.04 * std::min(w, h));
    const FrameResult& f = s.seq.frames[frame];
    compute::RenderStyle style;
    style.overlays = (o.draw_boundary ? compute::kOverlayBoundary : 0u) | (o.draw_distortion ? compute::kOverlayDistortion : 0u) |
                     (o.draw_handles ? compute::kOverlayHandles : 0u);
    for (int k = 0; k < 4; ++k) style.background[static_cast<size_t>(k)] = o.background[k];
    style.uncertified = !f.certified;
    const RgbaImage img = cache->renderer->render(s.seq.setup->cage, f.map, view, style);
    if (cache->context->validation_enabled() && cache->context->validation_log()->count() > 0)
      throw ApiError{HSI_ERROR_INTERNAL, "hsi_sequence_render: Vulkan validation reported problems:\n" +
                                             cache->context->validation_log()->summary(5)};
    for (int y = 0; y < h; ++y) std::memcpy(rgba + static_cast<size_t>(y) * row_stride, img.at(0, y), 4 * static_cast<size_t>(w));
  } catch (const compute::VulkanUnavailable& e) {
    cache->context.reset();
    throw ApiError{HSI_ERROR_UNSUPPORTED, std::string("hsi_sequence_render: no Vulkan device: ") + e.what()};
  } catch (const compute::VulkanError& e) {
    cache->renderer.reset();
    throw ApiError{HSI_ERROR_INTERNAL, std::string("hsi_sequence_render: Vulkan error: ") + e.what()};
  }
}

}  // namespace hsi::capi
