// Offscreen renderer (see renderer.h): construction, the rasterizer's choice, and the
// scene-side state (mesh, texture, given geometry). A frame is recorded in
// render_recording.cpp, by the passes of raster_graphics.cpp (the graphics pipeline:
// the mesh with 4x MSAA, lines, discs) and raster_compute.cpp (the compute
// rasterizer); render_view.cpp holds the Vulkan-free view and colour map. Colours are
// premultiplied throughout (texture, blending, clear colour) and un-premultiplied on
// the way out.
#include "hsi/compute/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "renderer_impl.h"

namespace hsi::compute {

namespace {

constexpr int kMaxSide = 16384;

// A device-local buffer holding `bytes` (through a staging copy unless the memory
// is host-visible).
Buffer static_buffer(const Context& ctx, VkBufferUsageFlags usage, const void* data, VkDeviceSize bytes) {
  Buffer b(ctx, std::max<VkDeviceSize>(bytes, 16), usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kDeviceLocal);
  if (bytes == 0) return b;
  if (b.host_visible()) {
    b.write(data, bytes);
    return b;
  }
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::kUpload);
  staging.write(data, bytes);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    const VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(cmd, staging.handle(), b.handle(), 1, &region);
    memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                   VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
  });
  return b;
}

// The vertex indices of a mesh's triangles or boundary edges, flattened; InputError
// naming the item (`what` and its index) with an index outside 0..vertices-1.
template <size_t K>
std::vector<uint32_t> vertex_indices(const std::vector<std::array<int, K>>& items, int vertices, const char* what) {
  std::vector<uint32_t> out;
  out.reserve(items.size() * K);
  for (size_t i = 0; i < items.size(); ++i)
    for (int v : items[i]) {
      if (v < 0 || v >= vertices)
        throw InputError(std::string("renderer: ") + what + " " + std::to_string(i) + " has vertex index " +
                         std::to_string(v) + " outside 0.." + std::to_string(vertices - 1));
      out.push_back(static_cast<uint32_t>(v));
    }
  return out;
}

// A sampled, mipmapped texture from straight-alpha RGBA (premultiplied on upload,
// mip levels by linear blits of the premultiplied colours).
Image upload_texture(const Context& ctx, const RgbaImage& src) {
  ImageInfo info;
  info.width = static_cast<uint32_t>(src.width);
  info.height = static_cast<uint32_t>(src.height);
  info.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  info.mips = mip_levels(info.width, info.height);
  Image tex(ctx, info);
  std::vector<uint8_t> pre(src.pixels.size());
  for (size_t i = 0; i < pre.size(); i += 4) {
    const unsigned a = src.pixels[i + 3];
    for (size_t c = 0; c < 3; ++c) pre[i + c] = static_cast<uint8_t>((src.pixels[i + c] * a + 127) / 255);
    pre[i + 3] = static_cast<uint8_t>(a);
  }
  Buffer staging(ctx, pre.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::kUpload);
  staging.write(pre.data(), pre.size());
  // Sampled by the mesh's fragment shader or the compute rasterizer's resolve pass.
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    tex.record_upload(cmd, staging, VK_IMAGE_LAYOUT_UNDEFINED,
                      VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  });
  return tex;
}

// The rasterizer and its samples per pixel (see Rasterizer): the compute rasterizer
// takes any of 1, 2, 4, 8 samples, but its visibility buffer must fit in one storage
// buffer; the graphics one what the device's framebuffers support.
struct RasterChoice {
  Rasterizer rasterizer;
  int samples;
};
RasterChoice choose_rasterizer(const Context& context, int width, int height, const RendererOptions& options) {
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(context.physical_device(), &props);
  const auto pick_samples = [&](VkSampleCountFlags supported) {
    for (int s : {8, 4, 2, 1})
      if (s <= options.msaa_samples && (supported & static_cast<VkSampleCountFlags>(s))) return s;
    return 1;
  };
  const int compute_samples = pick_samples(VK_SAMPLE_COUNT_1_BIT | VK_SAMPLE_COUNT_2_BIT | VK_SAMPLE_COUNT_4_BIT |
                                           VK_SAMPLE_COUNT_8_BIT);
  const uint64_t vis_bytes = render::ComputeRaster::visibility_bytes(
      static_cast<uint32_t>(width), static_cast<uint32_t>(height), static_cast<uint32_t>(compute_samples));
  const bool vis_fits = vis_bytes <= props.limits.maxStorageBufferRange;
  const RasterChoice graphics{Rasterizer::kGraphics, pick_samples(props.limits.framebufferColorSampleCounts)};
  switch (options.rasterizer) {
    case Rasterizer::kCompute:
      if (!vis_fits)
        throw VulkanError("renderer: the compute rasterizer's visibility buffer (" + std::to_string(width) + " x " +
                          std::to_string(height) + " pixels x " + std::to_string(compute_samples) + " samples x 4 bytes = " +
                          std::to_string(vis_bytes) + " bytes) exceeds " + context.info().name +
                          "'s maxStorageBufferRange (" + std::to_string(props.limits.maxStorageBufferRange) +
                          "); use fewer samples, a smaller image or the graphics rasterizer");
      return {Rasterizer::kCompute, compute_samples};
    case Rasterizer::kGraphics: return graphics;
    case Rasterizer::kAuto: break;
  }
  return !context.info().is_cpu() && vis_fits ? RasterChoice{Rasterizer::kCompute, compute_samples} : graphics;
}

}  // namespace

Renderer::~Renderer() = default;

Renderer::Renderer(const Context& context, int width, int height, const RendererOptions& options)
    : context_(&context), width_(width), height_(height), eval_(context, options.evaluation),
      impl_(std::make_unique<Impl>()) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw InputError("renderer: image size " + std::to_string(width) + " x " + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxSide));
  if (!context.info().can_draw())
    throw VulkanUnavailable("renderer: the Vulkan device " + context.info().name +
                            " has no queue that can both compute and draw");
  const RasterChoice choice = choose_rasterizer(context, width, height, options);
  rasterizer_ = choice.rasterizer;
  samples_ = choice.samples;
  const bool compute = rasterizer_ == Rasterizer::kCompute;
  const uint32_t w = static_cast<uint32_t>(width), h = static_cast<uint32_t>(height);
  Impl& r = *impl_;
  ImageInfo target;
  target.width = w;
  target.height = h;
  target.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                 (compute ? VkImageUsageFlags{VK_IMAGE_USAGE_STORAGE_BIT} : VkImageUsageFlags{0});
  r.target = Image(context, target);
  r.readback = Buffer(context, VkDeviceSize{w} * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kReadback);
  r.sampler = Sampler(context);
  r.white = upload_texture(context, RgbaImage(1, 1, {255, 255, 255, 255}));
  // The compute path draws its lines and discs into the resolved image, single-sampled.
  r.graphics.emplace(context, r.target, compute ? VK_SAMPLE_COUNT_1_BIT : static_cast<VkSampleCountFlagBits>(samples_),
                     compute, eval_.double_precision());
  if (compute) r.compute.emplace(context, w, h, static_cast<uint32_t>(samples_), eval_.double_precision());
}

void Renderer::set_mesh(const TriMesh& mesh, std::span<const cd> handles) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    throw InputError("renderer: the mesh is empty (" + std::to_string(mesh.vertices.size()) + " vertices, " +
                     std::to_string(mesh.triangles.size()) + " triangles)");
  const std::vector<uint32_t> indices = vertex_indices(mesh.triangles, mesh.vertex_count(), "triangle");
  const std::vector<uint32_t> segments = vertex_indices(mesh.boundary_edges, mesh.vertex_count(), "boundary edge");
  for (size_t k = 0; k < handles.size(); ++k)
    if (!std::isfinite(handles[k].real()) || !std::isfinite(handles[k].imag()))
      throw InputError("renderer: handle " + std::to_string(k) + " is not finite");
  Impl& r = *impl_;
  r.index = static_buffer(*context_, VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, indices.data(),
                          indices.size() * sizeof(uint32_t));
  if (r.compute) r.compute->set_triangles(mesh.triangles.size());
  r.segments = static_buffer(*context_, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, segments.data(),
                             segments.size() * sizeof(uint32_t));
  rest_vertices_ = mesh.vertices;
  points_ = mesh.vertices;
  points_.insert(points_.end(), handles.begin(), handles.end());
  vertex_count_ = mesh.vertices.size();
  handle_count_ = handles.size();
  index_count_ = indices.size();
  segment_count_ = mesh.boundary_edges.size();
  uv_dirty_ = true;
}

void Renderer::set_texture(const RgbaImage& texture, const std::array<double, 4>& rect, TextureFilter filter) {
  Impl& r = *impl_;
  if (filter != filter_) {  // frames bind the sampler when recorded; none is pending here
    SamplerInfo si;
    if (filter == TextureFilter::Nearest) {
      si.filter = VK_FILTER_NEAREST;
      si.mipmap = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    }
    r.sampler = Sampler(*context_, si);
    filter_ = filter;
  }
  if (texture.empty()) {
    r.texture = Image();
    has_texture_ = false;
    return;
  }
  if (texture.pixels.size() != static_cast<size_t>(texture.width) * static_cast<size_t>(texture.height) * 4)
    throw InputError("renderer: the texture's pixel data does not match its size");
  if (texture.width > kMaxSide || texture.height > kMaxSide)
    throw InputError("renderer: texture size " + std::to_string(texture.width) + " x " +
                     std::to_string(texture.height) + " is larger than " + std::to_string(kMaxSide));
  if (!(rect[2] > rect[0] && rect[3] > rect[1]) || !std::all_of(rect.begin(), rect.end(), [](double v) { return std::isfinite(v); }))
    throw InputError("renderer: the texture rectangle [x0, y0, x1, y1] needs x1 > x0 and y1 > y0, finite");
  r.texture = upload_texture(*context_, texture);
  texture_rect_ = rect;
  has_texture_ = true;
  uv_dirty_ = true;
}

void Renderer::upload_uv() {
  const auto& [x0, y0, x1, y1] = texture_rect_;
  std::vector<float> uv;
  uv.reserve(2 * rest_vertices_.size());
  for (const cd& p : rest_vertices_) {
    uv.push_back(static_cast<float>((p.real() - x0) / (x1 - x0)));
    uv.push_back(static_cast<float>((y1 - p.imag()) / (y1 - y0)));  // row 0 is the top (y1)
  }
  impl_->uv = static_buffer(*context_, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, uv.data(),
                            uv.size() * sizeof(float));
  uv_dirty_ = false;
}

size_t Renderer::upload_given(std::span<const cd> positions, std::span<const double> kappa,
                              std::span<const cd> handle_positions) {
  if (points_.empty()) throw InputError("renderer: no mesh (call set_mesh first)");
  if (positions.size() != vertex_count_ || kappa.size() != vertex_count_)
    throw InputError("renderer: given geometry needs one position and one distortion per mesh vertex (the mesh has " +
                     std::to_string(vertex_count_) + " vertices; got " + std::to_string(positions.size()) +
                     " positions, " + std::to_string(kappa.size()) + " distortion values)");
  if (!handle_positions.empty() && handle_positions.size() != handle_count_)
    throw InputError("renderer: " + std::to_string(handle_positions.size()) + " handle positions for " +
                     std::to_string(handle_count_) + " handles (give one per handle, or none)");
  for (size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i].real()) || !std::isfinite(positions[i].imag()))
      throw InputError("renderer: given position " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < handle_positions.size(); ++i)
    if (!std::isfinite(handle_positions[i].real()) || !std::isfinite(handle_positions[i].imag()))
      throw InputError("renderer: given handle position " + std::to_string(i) + " is not finite");
  Impl& r = *impl_;
  const size_t n = vertex_count_ + handle_count_;
  const bool f64 = eval_.double_precision();
  const size_t real = f64 ? sizeof(double) : sizeof(float);
  if (r.given_capacity < n) {
    r.given_f = Buffer(*context_, 2 * real * n, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    r.given_fields = Buffer(*context_, 4 * real * n, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    r.given_capacity = n;
  }
  // f[i] = (x, y); fields[i] = (σ1, σ2, κ, E_SD) as the evaluation writes them. Only κ
  // is read by the shaders; σ1, σ2 and E_SD are NaN (not known here). Handles without
  // given positions stay at their rest positions (their discs are not drawn).
  std::vector<double> f(2 * n), fields(4 * n, std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < n; ++i) {
    const cd p = i < vertex_count_ ? positions[i]
                 : handle_positions.empty() ? points_[i]
                                            : handle_positions[i - vertex_count_];
    f[2 * i] = p.real();
    f[2 * i + 1] = p.imag();
    fields[4 * i + 2] = i < vertex_count_ ? kappa[i] : 1.0;
  }
  if (f64) {
    r.given_f.write(f.data(), f.size() * sizeof(double));
    r.given_fields.write(fields.data(), fields.size() * sizeof(double));
  } else {
    const std::vector<float> f32(f.begin(), f.end()), fields32(fields.begin(), fields.end());
    r.given_f.write(f32.data(), f32.size() * sizeof(float));
    r.given_fields.write(fields32.data(), fields32.size() * sizeof(float));
  }
  return handle_positions.size();
}

void Renderer::check_frame(const View& view, const RenderStyle& style) const {
  if (points_.empty()) throw InputError("renderer: no mesh (call set_mesh first)");
  if (!(view.pixels_per_unit > 0) || !std::isfinite(view.pixels_per_unit))
    throw InputError("renderer: the view needs a finite positive scale");
  if (!(style.distortion_hi > style.distortion_lo))
    throw InputError("renderer: the distortion range needs hi > lo (got " + std::to_string(style.distortion_lo) +
                     ", " + std::to_string(style.distortion_hi) + ")");
}

}  // namespace hsi::compute
