// hsi render SCENE FRAMES_DIR -o OUT/: draws the frames of `hsi interpolate` offscreen
// (Vulkan; lavapipe where there is no GPU): the deformed shape with its texture, the
// chosen overlays, a distortion legend and frame labels (cairo, composited here so
// that compute/ stays free of text), as a numbered PNG sequence and a contact sheet.
// Built where compute/ is (cli/CMakeLists.txt); elsewhere cmd_render_unavailable.cpp
// registers the command with runtime/'s reason.
#include <cairo.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include "commands.h"
#include "hsi/basis.h"
#include "hsi/compute/renderer.h"
#include "hsi/draw/raster.h"
#include "hsi/frames_io.h"
#include "hsi/scene_io.h"
#include "hsi/scene_texture.h"
#include "hsi/triangulate.h"

namespace hsi::cli {

namespace {

using draw::draw_legend;
using draw::fmt;
using draw::make_surface;
using draw::Surface;
using draw::surface_from;
using draw::text;
using draw::text_width;
using draw::write_surface;

using Clock = std::chrono::steady_clock;

struct Opts {
  std::string scene, frames_dir, out;
  std::string size = "1024";
  std::vector<std::string> overlays = {"boundary"};
  std::string frames = "all";
  int every = 1;
  std::vector<double> distortion_range;
  std::string background = "white";
  bool no_texture = false, no_sheet = false, no_labels = false, validation = false;
  int mesh_vertices = 20000, sheet_max = 24, sheet_columns = 0;
  std::string device;
  std::string rasterizer = "auto";
  std::string filter = "scene";  // the scene's texture_filter, or linear / nearest
};

// "all", or comma-separated indices and inclusive ranges a-b ("0,10,20-30").
std::vector<int> parse_frames(const std::string& spec, int count) {
  std::vector<int> out;
  if (spec == "all") {
    for (int i = 0; i < count; ++i) out.push_back(i);
    return out;
  }
  std::stringstream ss(spec);
  std::string item;
  auto number = [&](const std::string& s) {
    size_t used = 0;
    int v = -1;
    try {
      v = std::stoi(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != s.size() || s.empty() || v < 0)
      throw InputError("--frames: '" + s + "' in '" + spec + "' is not a frame index (use e.g. all, 0,10,20-30)");
    if (v >= count)
      throw InputError("--frames: frame " + std::to_string(v) + " does not exist (the file has " +
                       std::to_string(count) + " frames, 0.." + std::to_string(count - 1) + ")");
    return v;
  };
  while (std::getline(ss, item, ',')) {
    const size_t dash = item.find('-');
    if (dash == std::string::npos) {
      out.push_back(number(item));
    } else {
      const int a = number(item.substr(0, dash)), b = number(item.substr(dash + 1));
      if (b < a) throw InputError("--frames: range " + item + " is empty (write the lower index first)");
      for (int i = a; i <= b; ++i) out.push_back(i);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  if (out.empty()) throw InputError("--frames: '" + spec + "' selects no frames");
  return out;
}

uint32_t parse_overlays(const std::vector<std::string>& items) {
  uint32_t o = 0;
  for (const std::string& list : items) {
    std::stringstream ss(list);
    std::string s;
    while (std::getline(ss, s, ',')) {
      if (s == "distortion") o |= compute::kOverlayDistortion;
      else if (s == "boundary") o |= compute::kOverlayBoundary;
      else if (s == "handles") o |= compute::kOverlayHandles;
      else if (s == "none" || s.empty()) continue;
      else throw InputError("--overlay: unknown overlay '" + s + "' (distortion, boundary, handles or none)");
    }
  }
  return o;
}

std::array<float, 4> parse_colour(const std::string& s) {
  if (s == "white") return {1, 1, 1, 1};
  if (s == "black") return {0, 0, 0, 1};
  if (s == "transparent") return {1, 1, 1, 0};
  if (s.size() == 7 && s[0] == '#') {
    try {
      const unsigned long v = std::stoul(s.substr(1), nullptr, 16);
      return {static_cast<float>((v >> 16) & 255) / 255, static_cast<float>((v >> 8) & 255) / 255,
              static_cast<float>(v & 255) / 255, 1};
    } catch (const std::exception&) {
    }
  }
  throw InputError("--background: '" + s + "' is not a colour (white, black, transparent or #rrggbb)");
}

void check_frames_match(const Scene& scene, const std::string& scene_path, const FrameFile& ff, const std::string& frames_path) {
  const Cage sc = scene_cage(scene);
  auto describe = [](const Cage& c) {
    return std::to_string(c.loops.size()) + " cage loops, m = " + std::to_string(c.vertex_count()) + " cage vertices and N = " +
           std::to_string(c.hole_count()) + " holes (" + std::to_string(c.vertex_count() + c.hole_count()) +
           " coefficients per map)";
  };
  bool sizes = sc.loops.size() == ff.cage.loops.size() && sc.hole_points.size() == ff.cage.hole_points.size();
  for (size_t l = 0; sizes && l < sc.loops.size(); ++l) sizes = sc.loops[l].size() == ff.cage.loops[l].size();
  if (!sizes)
    throw InputError(frames_path + " does not belong to " + scene_path + ": its frames are maps over a cage with " +
                     describe(ff.cage) + ", the scene's cage has " + describe(sc) +
                     "; run hsi interpolate on this scene again");
  bool same = true;
  const double tol = 1e-9 * std::max(1.0, bounding_box(scene.shape).diagonal());
  for (size_t l = 0; same && l < sc.loops.size(); ++l)
    for (size_t i = 0; same && i < sc.loops[l].size(); ++i) same = std::abs(sc.loops[l][i] - ff.cage.loops[l][i]) <= tol;
  for (size_t i = 0; same && i < sc.hole_points.size(); ++i) same = std::abs(sc.hole_points[i] - ff.cage.hole_points[i]) <= tol;
  if (!same)
    throw InputError(frames_path + " does not belong to " + scene_path +
                     ": its cage has the scene's sizes but other vertex positions (the scene or its cage changed since "
                     "hsi interpolate ran); run hsi interpolate on this scene again");
}

void run_render(const Opts& o) {
  const auto t_start = Clock::now();
  const Scene scene = load_scene(o.scene);
  const std::filesystem::path dir(o.frames_dir);
  const std::filesystem::path frames_path = dir / "frames.hsif";
  if (!std::filesystem::exists(frames_path))
    throw InputError(frames_path.string() + " not found: FRAMES_DIR must be the output folder of hsi interpolate");
  const FrameFile ff = read_frames(frames_path);
  if (ff.frames.empty()) throw InputError(frames_path.string() + " holds no frames");
  check_frames_match(scene, o.scene, ff, frames_path.string());
  const std::vector<int> selected_all = parse_frames(o.frames, static_cast<int>(ff.frames.size()));
  std::vector<int> selected;
  for (size_t i = 0; i < selected_all.size(); i += static_cast<size_t>(o.every)) selected.push_back(selected_all[i]);
  const uint32_t overlays = parse_overlays(o.overlays);
  const std::array<float, 4> background = parse_colour(o.background);
  if (!o.distortion_range.empty() && !(o.distortion_range.size() == 2 && o.distortion_range[1] > o.distortion_range[0]))
    throw InputError("--distortion-range needs two numbers LO HI with HI > LO");

  // Texture: the scene's, or a checkerboard with --no-texture / when the scene has none.
  const SceneTexture st = scene_texture(scene, o.scene, o.no_texture, true, "render with --no-texture");
  const RgbaImage& texture = st.image;
  const std::array<double, 4>& rect = st.rect;
  if (st.checker && !o.no_texture) std::printf("scene %s has no texture: drawing a checkerboard instead\n", scene.name.c_str());

  // The rest mesh: boundary vertices on the shape's edges, so the outline clips exactly.
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(scene.shape, o.mesh_vertices);
  const TriMesh mesh = triangulate(scene.shape, to);

  // Per frame on the CPU, at the mesh's boundary vertices and the handles: the image's
  // bounding box (one view for the whole sequence, so it does not jump) and the
  // largest conformal distortion (attained on the boundary, Theorem 2).
  std::vector<cd> probe;
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.boundary_loop[static_cast<size_t>(v)] >= 0) probe.push_back(mesh.vertices[static_cast<size_t>(v)]);
  probe.insert(probe.end(), scene.handles.begin(), scene.handles.end());
  const BasisRows rows = evaluate_basis(ff.cage, probe, kBasisC | kBasisD);
  BoundingBox box{cd(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()),
                  cd(-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity())};
  double kappa_max = 1;
  for (int i : selected) {
    const MapValues v = evaluate_map(rows, ff.frames[static_cast<size_t>(i)].map);
    for (Eigen::Index k = 0; k < v.f.size(); ++k) {
      const cd z = v.f(k);
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) continue;
      box.lo = {std::min(box.lo.real(), z.real()), std::min(box.lo.imag(), z.imag())};
      box.hi = {std::max(box.hi.real(), z.real()), std::max(box.hi.imag(), z.imag())};
      const double a = std::abs(v.f_z(k)), b = std::abs(v.fzbar_conj(k));
      if (a > b) kappa_max = std::max(kappa_max, (a + b) / (a - b));
    }
  }
  if (!std::isfinite(box.lo.real())) throw InputError(frames_path.string() + ": the selected frames map the shape to non-finite points");
  const double lo = o.distortion_range.empty() ? 1.0 : o.distortion_range[0];
  const double hi = o.distortion_range.empty() ? compute::round_distortion_hi(kappa_max) : o.distortion_range[1];

  // Image size and layout: margins for the labels, a strip for the legend.
  int W = 0, H = 0;
  const size_t x = o.size.find('x');
  try {
    if (x == std::string::npos) {
      W = H = std::stoi(o.size);
    } else {
      W = std::stoi(o.size.substr(0, x));
      H = std::stoi(o.size.substr(x + 1));
    }
  } catch (const std::exception&) {
    W = H = 0;
  }
  if (W < 64 || H < 64 || W > 8192 || H > 8192)
    throw InputError("--size: '" + o.size + "' is not a size between 64 and 8192 (e.g. 1024 or 1280x720)");
  const bool legend = (overlays & compute::kOverlayDistortion) != 0;
  const int longer = std::max(W, H);
  const double font = std::max(11.0, longer / 56.0);
  const double margin = std::max(12.0, 0.05 * longer) + (o.no_labels ? 0 : 0.5 * font);
  const double strip = legend ? 3.2 * font : 0;
  if (x == std::string::npos) {  // --size S: the longer side S, the other one fitted to the sequence's extent
    const cd ext = box.hi - box.lo;
    const double aspect = std::max(ext.real(), 1e-12) / std::max(ext.imag(), 1e-12);
    if (aspect >= 1) {
      H = static_cast<int>(std::ceil((W - 2 * margin) / aspect + 2 * margin + strip));
      H = std::clamp(H + H % 2, std::min(W, static_cast<int>(2 * margin + strip + 4 * font)), W);
    } else {
      W = static_cast<int>(std::ceil((H - 2 * margin - strip) * aspect + 2 * margin));
      W = std::clamp(W + W % 2, std::min(H, static_cast<int>(2 * margin + 30 * font)), H);
    }
  }
  const compute::View view = compute::View::fit(box, W, H, margin, strip);

  // Vulkan.
  compute::ContextOptions co;
  co.validation = o.validation;
  co.device_name = o.device;
  std::unique_ptr<compute::Context> ctx;
  try {
    ctx = std::make_unique<compute::Context>(co);
  } catch (const compute::VulkanUnavailable& e) {
    throw std::runtime_error(std::string("hsi render needs a Vulkan device (a GPU, or lavapipe on the CPU): ") + e.what());
  }
  compute::RendererOptions ro;
  ro.rasterizer = o.rasterizer == "graphics" ? compute::Rasterizer::kGraphics
                  : o.rasterizer == "compute" ? compute::Rasterizer::kCompute
                                              : compute::Rasterizer::kAuto;
  compute::Renderer renderer(*ctx, W, H, ro);
  renderer.set_mesh(mesh, scene.handles);
  const TextureFilter filter = o.filter == "scene" ? st.filter : *parse_texture_filter(o.filter);
  renderer.set_texture(texture, rect, filter);
  std::printf("rendering %zu of %zu frames at %d x %d on %s (%s, %s precision, %dx MSAA, %s rasterizer, %s texture "
              "filtering); mesh %d vertices, %d triangles\n",
              selected.size(), ff.frames.size(), W, H, ctx->info().name.c_str(), ctx->info().type_name().c_str(),
              renderer.double_precision() ? "double" : "float", renderer.msaa_samples(),
              renderer.rasterizer() == compute::Rasterizer::kCompute ? "compute" : "graphics", texture_filter_name(filter),
              mesh.vertex_count(), mesh.triangle_count());
  if (legend) std::printf("distortion colour map over [%.3f, %.3f] (largest in these frames: %.4f)\n", lo, hi, kappa_max);
  std::fflush(stdout);

  const std::filesystem::path out(o.out.empty() ? (dir / "render").string() : o.out);
  std::filesystem::create_directories(out);
  compute::RenderStyle style;
  style.overlays = overlays;
  style.background = background;
  style.distortion_lo = lo;
  style.distortion_hi = hi;
  style.boundary_width_px = static_cast<float>(std::max(1.5, longer / 512.0));
  style.handle_radius_px = static_cast<float>(std::max(4.0, longer / 160.0));
  style.handle_outline_px = static_cast<float>(std::max(1.0, longer / 700.0));

  // Contact sheet: up to sheet_max frames evenly spaced over the selection.
  std::vector<size_t> sheet_at;
  if (!o.no_sheet) {
    const size_t n = std::min(selected.size(), static_cast<size_t>(std::max(1, o.sheet_max)));
    for (size_t k = 0; k < n; ++k) sheet_at.push_back(n == 1 ? 0 : k * (selected.size() - 1) / (n - 1));
  }
  const int cols = o.sheet_columns > 0 ? o.sheet_columns
                                       : std::max(1, std::min(static_cast<int>(sheet_at.size()), static_cast<int>(std::ceil(std::sqrt(static_cast<double>(sheet_at.size()) * 1.6 * H / W)))));
  const double thumb_scale = std::min(1.0, 320.0 / std::max(W, H));
  const int tw = std::max(1, static_cast<int>(W * thumb_scale)), th = std::max(1, static_cast<int>(H * thumb_scale));
  const int rows_n = sheet_at.empty() ? 0 : static_cast<int>((sheet_at.size() + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  const int pad = 10, cap = 22, title_h = 40;
  Surface sheet;
  if (!sheet_at.empty()) {
    sheet = make_surface(cols * (tw + pad) + pad, title_h + rows_n * (th + cap + pad) + pad);
    cairo_set_source_rgb(sheet.cr(), 0.96, 0.96, 0.96);
    cairo_paint(sheet.cr());
  }

  const int digits = std::max(4, static_cast<int>(std::to_string(ff.frames.size() - 1).size()));
  const bool tty = isatty(fileno(stderr));
  int uncertified = 0;
  int overlapping = 0;  // frames flagged 8 in frames.hsif: the boundary's image crosses itself
  int not_converged = 0;  // Newton stopped before its tolerance (frames file flag 4 clear)
  std::vector<std::optional<NewtonStop>> rendered_stops;  // why, per rendered frame (the frames file's stop code)
  size_t next_sheet = 0;
  double render_ms = 0;
  for (size_t s = 0; s < selected.size(); ++s) {
    const int i = selected[s];
    const StoredFrame& fr = ff.frames[static_cast<size_t>(i)];
    style.uncertified = !fr.certified;
    uncertified += !fr.certified;
    overlapping += fr.overlaps;
    not_converged += !fr.converged;
    const std::optional<NewtonStop> stop = stored_stop(fr, static_cast<size_t>(i));
    rendered_stops.push_back(stop);
    const RgbaImage img = renderer.render(ff.cage, fr.map, view, style);
    render_ms += renderer.last_stats().gpu_ms + renderer.last_stats().upload_ms + renderer.last_stats().readback_ms;
    const Surface surf = surface_from(img);
    if (fr.overlaps) {  // an amber border (inside the red one of an uncertified frame): not globally injective
      const double b = std::max(4.0, std::min(W, H) / 64.0);
      cairo_t* cr = surf.cr();
      cairo_set_source_rgb(cr, 0.96, 0.58, 0.0);
      cairo_set_line_width(cr, b);
      const double inset = (fr.certified ? 0.5 : 1.5) * b;
      cairo_rectangle(cr, inset, inset, W - 2 * inset, H - 2 * inset);
      cairo_stroke(cr);
    }
    if (!sheet_at.empty() && next_sheet < sheet_at.size() && sheet_at[next_sheet] == s) {
      const int k = static_cast<int>(next_sheet++);
      const double x0 = pad + (k % cols) * (tw + pad), y0 = title_h + (k / cols) * (th + cap + pad);
      cairo_t* cr = sheet.cr();
      cairo_save(cr);
      cairo_rectangle(cr, x0, y0, tw, th);
      cairo_clip(cr);
      cairo_translate(cr, x0, y0);
      cairo_scale(cr, static_cast<double>(tw) / W, static_cast<double>(th) / H);
      cairo_set_source_surface(cr, surf.surf.get(), 0, 0);
      cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_GOOD);
      cairo_paint(cr);
      cairo_restore(cr);
      cairo_rectangle(cr, x0 - 0.5, y0 - 0.5, tw + 1, th + 1);
      if (!fr.certified)
        cairo_set_source_rgb(cr, 0.86, 0.04, 0.04);
      else if (fr.overlaps)
        cairo_set_source_rgb(cr, 0.96, 0.58, 0.0);
      else if (!fr.converged)
        cairo_set_source_rgb(cr, 0.95, 0.5, 0.0);
      else
        cairo_set_source_rgb(cr, 0.7, 0.7, 0.7);
      cairo_set_line_width(cr, fr.certified && fr.converged && !fr.overlaps ? 1 : 3);
      cairo_stroke(cr);
      std::string label = "#" + std::to_string(i) + "  t = " + fmt("%.3f", fr.t) + (fr.keyframe ? "  key" : "");
      if (!fr.certified) label += "  NOT CERTIFIED";
      text(cr, x0, y0 + th + 15, label, 12, !fr.certified, fr.certified ? 0.15 : 0.8, fr.certified ? 0.15 : 0.0,
           fr.certified ? 0.15 : 0.0, false);
      if (fr.overlaps) {
        const std::string ov = "OVERLAPS ITSELF";
        text(cr, x0 + tw - text_width(cr, ov, 11, true), y0 + th + 15, ov, 11, true, 0.85, 0.45, 0.0, false);
      }
      if (!fr.converged)
        text(cr, x0 + text_width(cr, label + "  ", 12, !fr.certified), y0 + th + 15, "NOT CONVERGED", 12, true, 0.9, 0.45, 0.0, false);
    }
    if (!o.no_labels) {
      cairo_t* cr = surf.cr();
      const double y = std::max(margin - 0.35 * font, 1.2 * font);
      std::string label = "frame " + std::to_string(i) + " / " + std::to_string(ff.frames.size() - 1) + "   t = " + fmt("%.4f", fr.t);
      if (fr.keyframe) label += "   keyframe";
      text(cr, 0.6 * font + (fr.certified ? 0 : 0.4 * font), y, label, font, false, 0.1, 0.1, 0.1);
      if (!fr.certified) {
        const std::string warn = "NOT CERTIFIED";
        text(cr, W - text_width(cr, warn, 1.3 * font, true) - font, y + 0.2 * font, warn, 1.3 * font, true, 0.86, 0.04, 0.04);
      }
      if (!fr.converged) {  // below NOT CERTIFIED when both
        const std::string warn = "NOT CONVERGED";
        text(cr, W - text_width(cr, warn, 1.3 * font, true) - font, y + (fr.certified ? 0.2 : 1.7) * font, warn, 1.3 * font, true,
             0.9, 0.45, 0.0);
      }
      if (fr.overlaps) {  // amber, right-aligned: on the label's line when it fits, else below (and below NOT CERTIFIED / CONVERGED)
        const std::string warn = "OVERLAPS ITSELF";
        const bool fits = fr.certified && fr.converged &&
                          0.6 * font + text_width(cr, label, font, false) + text_width(cr, warn, 1.3 * font, true) + 2 * font < W;
        const double below = (fr.certified ? 1.6 : 3.0) + (fr.converged ? 0.0 : 1.5);
        const double yo = fits ? y + 0.2 * font : y + below * font;
        text(cr, W - text_width(cr, warn, 1.3 * font, true) - font, yo, warn, 1.3 * font, true, 0.9, 0.5, 0.0);
      }
      if (legend) draw_legend(cr, W, H, margin + strip, lo, hi, font);
    }
    char name[64];
    std::snprintf(name, sizeof name, "frame_%0*d.png", digits, i);
    write_surface(surf, out / name);

    const double el = std::chrono::duration<double>(Clock::now() - t_start).count();
    const size_t done = s + 1, n = selected.size();
    if (tty)
      std::fprintf(stderr, "\r[render] frame %zu/%zu (#%d)  %.1f ms  %s   ", done, n, i,
                   renderer.last_stats().gpu_ms + renderer.last_stats().readback_ms,
                   (std::string(fr.certified ? "" : "NOT CERTIFIED ") +
                    (fr.converged ? "" : std::string("NOT CONVERGED (") + stop_name(stop) + ")"))
                       .c_str());
    else if (done % std::max<size_t>(1, n / 10) == 0 || done == n)
      std::fprintf(stderr, "[render] frame %zu/%zu (%.0f%%), %.1f s elapsed\n", done, n, 100.0 * static_cast<double>(done) / static_cast<double>(n), el);
  }
  if (tty) std::fprintf(stderr, "\n");

  if (!sheet_at.empty()) {
    std::string title = (scene.name.empty() ? o.scene : scene.name) + ": " + std::to_string(sheet_at.size()) + " of " +
                        std::to_string(ff.frames.size()) + " frames";
    if (uncertified) title += "   " + std::to_string(uncertified) + " NOT CERTIFIED (red)";
    if (overlapping) title += "   " + std::to_string(overlapping) + " OVERLAP ITSELF (amber)";
    text(sheet.cr(), pad, 26, title, 16, true, uncertified ? 0.8 : 0.1, 0.1, 0.1, false);
    if (not_converged)
      text(sheet.cr(), pad + text_width(sheet.cr(), title + "   ", 16, true), 26,
           std::to_string(not_converged) + " NOT CONVERGED (orange)", 16, true, 0.9, 0.45, 0.0, false);
    write_surface(sheet, out / "contact_sheet.png");
  }
  if (ctx->validation_enabled() && ctx->validation_log()->count())
    throw std::runtime_error("Vulkan validation reported problems:\n" + ctx->validation_log()->summary(10));
  std::printf("wrote %zu frames (%s/frame_%s.png)%s to %s in %.1f s (%.1f ms per frame on the device)\n", selected.size(),
              out.string().c_str(), std::string(static_cast<size_t>(digits), 'N').c_str(),
              sheet_at.empty() ? "" : " and contact_sheet.png", out.string().c_str(),
              std::chrono::duration<double>(Clock::now() - t_start).count(), render_ms / static_cast<double>(selected.size()));
  if (uncertified)
    std::printf("%d of the rendered frames are NOT CERTIFIED: they are drawn tinted red with a red border and labelled\n",
                uncertified);
  if (overlapping)
    std::printf("%d of the rendered frames OVERLAP ITSELF (certified locally injective at most, the boundary's image crosses "
                "itself): amber border and label\n",
                overlapping);
  if (not_converged)
    std::printf("%d of the rendered frames are NOT CONVERGED (the Newton solve stopped before its tolerance: %s): labelled in orange\n",
                not_converged, stop_counts(rendered_stops).c_str());
}

}  // namespace

void register_render(CLI::App& app) {
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("render", kRenderHelp);
  cmd->add_option("scene", o->scene, "Scene file (.json) the frames were computed for")->required()->check(CLI::ExistingFile);
  cmd->add_option("frames_dir", o->frames_dir, "Output folder of hsi interpolate (holds frames.hsif)")->required();
  cmd->add_option("-o,--output", o->out, "Output folder (default: FRAMES_DIR/render)");
  cmd->add_option("--size", o->size, "Image size: S (longer side S, the other fitted to the shape) or WxH")->capture_default_str();
  cmd->add_option("--overlay", o->overlays, "Overlays, comma-separated or repeated: distortion, boundary, handles, none")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames to render: all, or indices and ranges like 0,10,20-30")->capture_default_str();
  cmd->add_option("--every", o->every, "Render every K-th of the selected frames")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--distortion-range", o->distortion_range, "Colour map range LO HI of σ1/σ2 (default: 1 to the largest)")
      ->expected(2);
  cmd->add_option("--background", o->background, "white, black, transparent or #rrggbb")->capture_default_str();
  cmd->add_flag("--no-texture", o->no_texture, "Draw a checkerboard instead of the scene's texture");
  cmd->add_flag("--no-contact-sheet", o->no_sheet, "Do not write contact_sheet.png");
  cmd->add_option("--sheet-frames", o->sheet_max, "Frames on the contact sheet at most (evenly spaced)")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--sheet-columns", o->sheet_columns, "Contact sheet columns (default: fitted)");
  cmd->add_flag("--no-labels", o->no_labels, "No frame labels or legend on the frames");
  cmd->add_option("--mesh-vertices", o->mesh_vertices, "Vertices of the render mesh (about)")->capture_default_str()->check(CLI::Range(100, 5000000));
  cmd->add_option("--device", o->device, "Vulkan device name substring (default: HSI_VULKAN_DEVICE, else the best)");
  cmd->add_flag("--validation", o->validation, "Run with the Vulkan validation layer; fail on any message");
  cmd->add_option("--rasterizer", o->rasterizer,
                  "Triangles to pixels: auto (compute shaders on a GPU, the graphics pipeline on a CPU device), "
                  "graphics or compute")
      ->check(CLI::IsMember({"auto", "graphics", "compute"}))
      ->capture_default_str();
  cmd->add_option("--filter", o->filter,
                  "Texture filtering: scene (the scene's \"texture_filter\", linear unless it says nearest), linear "
                  "(bilinear) or nearest (crisp texels, for pixel art)")
      ->check(CLI::IsMember({"scene", "linear", "nearest"}))
      ->capture_default_str();
  cmd->callback([o] { run_render(*o); });
}

}  // namespace hsi::cli
