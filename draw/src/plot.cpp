// Cairo drawings for diagnostics (plot.h); kept out of engine/, which depends on no drawing library.
#include "hsi/draw/plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "hsi/triangulate.h"
#include "rgba_surface.h"

namespace hsi::draw {
namespace {
struct Frame {
  cd lo;
  double scale;
  int w, h;
  double pad;
  cd px(cd p) const { return {pad + (p.real() - lo.real()) * scale, h - pad - (p.imag() - lo.imag()) * scale}; }
};
// A white RGBA image with its drawing context; write() saves it as PNG.
class Canvas {
 public:
  Canvas(int w, int h)
      : surf_(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h), cairo_surface_destroy),
        ctx_(cairo_create(surf_.get()), cairo_destroy) {
    cairo_set_source_rgb(cr(), 1, 1, 1);
    cairo_paint(cr());
  }
  cairo_t* cr() const { return ctx_.get(); }
  void write(const std::filesystem::path& png) const {
    cairo_surface_flush(surf_.get());
    if (cairo_surface_write_to_png(surf_.get(), png.string().c_str()) != CAIRO_STATUS_SUCCESS)
      throw std::runtime_error("cannot write " + png.string());
  }

 private:
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surf_;
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> ctx_;
};

// A cairo surface (premultiplied ARGB32) of a straight-alpha RGBA image.
std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> texture_surface(const RgbaImage& img) {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> s(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, img.width, img.height), cairo_surface_destroy);
  detail::write_premultiplied(img, s.get());
  return s;
}

// The current source: the texture surface, sampled with the scene's filter, edges padded.
void set_texture_source(cairo_t* cr, cairo_surface_t* tex, TextureFilter filter) {
  cairo_set_source_surface(cr, tex, 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), filter == TextureFilter::Nearest ? CAIRO_FILTER_NEAREST : CAIRO_FILTER_BILINEAR);
  cairo_pattern_set_extend(cairo_get_source(cr), CAIRO_EXTEND_PAD);
}

// Texel coordinates (x right, y down, in texels) of a world point under texture rect r.
cd texel_of(const SceneTexture& t, cd p) {
  const auto& r = t.rect;
  return {(p.real() - r[0]) / (r[2] - r[0]) * t.image.width, (r[3] - p.imag()) / (r[3] - r[1]) * t.image.height};
}

void path(cairo_t* cr, const Frame& f, const Loop& loop) {
  for (size_t i = 0; i < loop.size(); ++i) {
    const cd q = f.px(loop[i]);
    if (i == 0)
      cairo_move_to(cr, q.real(), q.imag());
    else
      cairo_line_to(cr, q.real(), q.imag());
  }
  cairo_close_path(cr);
}
}  // namespace

void plot_cage(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const BoundarySamples* samples,
               int width_px, const CagePlot& extras) {
  const SceneTexture* texture = extras.texture;
  BoundingBox bb = bounding_box(cage.loops.front());
  const double pad = 20;
  const double sx = bb.hi.real() - bb.lo.real(), sy = bb.hi.imag() - bb.lo.imag();
  const double scale = (width_px - 2 * pad) / std::max(sx, 1e-300);
  const int height_px = static_cast<int>(std::ceil(sy * scale + 2 * pad));
  const Frame f{bb.lo, scale, width_px, height_px, pad};
  const Canvas canvas(width_px, height_px);
  cairo_t* cr = canvas.cr();
  const bool textured = texture && !texture->checker && !texture->image.empty();
  if (textured) {  // the sprite under everything: texel (0, 0) at the rectangle's top-left corner
    const auto tex = texture_surface(texture->image);
    const auto& r = texture->rect;
    const cd top_left = f.px({r[0], r[3]});
    cairo_save(cr);
    cairo_translate(cr, top_left.real(), top_left.imag());
    cairo_scale(cr, (r[2] - r[0]) * scale / texture->image.width, (r[3] - r[1]) * scale / texture->image.height);
    set_texture_source(cr, tex.get(), texture->filter);
    cairo_pattern_set_extend(cairo_get_source(cr), CAIRO_EXTEND_NONE);
    cairo_paint(cr);
    cairo_restore(cr);
  }
  // Shape, filled with holes cut out (even-odd); over a texture only tinted.
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
  for (int k = 0; k < shape.loop_count(); ++k) path(cr, f, shape.loop(k));
  cairo_set_source_rgba(cr, 0.78, 0.86, 0.95, textured ? 0.25 : 1.0);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.15, 0.3, 0.55);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
  // Cage: dashed red polygons with vertices.
  const double dash[] = {6.0, 4.0};
  cairo_set_dash(cr, dash, 2, 0);
  cairo_set_source_rgb(cr, 0.85, 0.15, 0.1);
  for (const Loop& l : cage.loops) {
    path(cr, f, l);
    cairo_stroke(cr);
  }
  cairo_set_dash(cr, nullptr, 0, 0);
  for (const Loop& l : cage.loops)
    for (const cd& z : l) {
      const cd q = f.px(z);
      cairo_arc(cr, q.real(), q.imag(), 2.5, 0, 2 * M_PI);
      cairo_fill(cr);
    }
  // Hole points: crosses.
  cairo_set_source_rgb(cr, 0.1, 0.55, 0.2);
  cairo_set_line_width(cr, 2);
  for (const cd& rho : cage.hole_points) {
    const cd q = f.px(rho);
    cairo_move_to(cr, q.real() - 5, q.imag() - 5);
    cairo_line_to(cr, q.real() + 5, q.imag() + 5);
    cairo_move_to(cr, q.real() - 5, q.imag() + 5);
    cairo_line_to(cr, q.real() + 5, q.imag() - 5);
    cairo_stroke(cr);
  }
  for (size_t k = 0; k < extras.handles.size(); ++k) {  // handles: red dots with their index
    const cd q = f.px(extras.handles[k]);
    cairo_set_source_rgb(cr, 0.8, 0.1, 0.1);
    cairo_arc(cr, q.real(), q.imag(), 4, 0, 2 * M_PI);
    cairo_fill(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 12);
    cairo_move_to(cr, q.real() + 6, q.imag() - 6);
    cairo_show_text(cr, std::to_string(k).c_str());
  }
  if (samples) {
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    const size_t stride = std::max<size_t>(1, samples->size() / 600);
    for (size_t i = 0; i < samples->size(); i += stride) {
      const cd q = f.px(samples->points[i]);
      cairo_arc(cr, q.real(), q.imag(), 1.2, 0, 2 * M_PI);
      cairo_fill(cr);
    }
  }
  canvas.write(png);
}

}  // namespace hsi::draw

namespace hsi::draw {

void plot_map(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const HarmonicMap& map,
              const MapPlot& extras, int width_px) {
  // Boundary images (dense) and grid lines inside the rest shape.
  const BoundarySamples dense = sample_boundary(shape, 4000);
  std::vector<std::vector<cd>> lines;
  const BoundingBox bb = bounding_box(shape);
  const int count = 24;
  const double step = std::max(bb.hi.real() - bb.lo.real(), bb.hi.imag() - bb.lo.imag()) / count;
  const double fine = step / 12;
  for (int dir = 0; dir < 2; ++dir) {
    const double lo = dir == 0 ? bb.lo.real() : bb.lo.imag(), hi = dir == 0 ? bb.hi.real() : bb.hi.imag();
    const double lo2 = dir == 0 ? bb.lo.imag() : bb.lo.real(), hi2 = dir == 0 ? bb.hi.imag() : bb.hi.real();
    for (double u = lo + step / 2; u < hi; u += step) {
      std::vector<cd> run;
      for (double w = lo2; w <= hi2 + fine / 2; w += fine) {
        const cd p = dir == 0 ? cd(u, w) : cd(w, u);
        if (point_in_shape(shape, p)) {
          run.push_back(p);
        } else if (!run.empty()) {
          lines.push_back(run);
          run.clear();
        }
      }
      if (!run.empty()) lines.push_back(run);
    }
  }
  std::vector<cd> pts = dense.points;
  for (const auto& l : lines) pts.insert(pts.end(), l.begin(), l.end());
  const VectorXcd f = evaluate_map(evaluate_basis(cage, pts, kBasisC), map).f;

  double inf = std::numeric_limits<double>::infinity();
  cd lo(inf, inf), hi(-inf, -inf);
  auto grow = [&](cd p) {
    lo = {std::min(lo.real(), p.real()), std::min(lo.imag(), p.imag())};
    hi = {std::max(hi.real(), p.real()), std::max(hi.imag(), p.imag())};
  };
  for (Eigen::Index i = 0; i < f.size(); ++i) grow(f(i));
  for (const cd& t : extras.targets) grow(t);
  const double pad = 24, title_h = extras.title.empty() ? 0 : 22;
  const double sx = hi.real() - lo.real(), sy = hi.imag() - lo.imag();
  const double scale = (width_px - 2 * pad) / std::max({sx, sy * 0.75, 1e-300});
  const int height_px = static_cast<int>(std::ceil(sy * scale + 2 * pad + title_h));
  const Frame fr{lo, scale, width_px, height_px, pad};
  const Canvas canvas(width_px, height_px);
  cairo_t* cr = canvas.cr();
  const bool textured = extras.texture && !extras.texture->checker && !extras.texture->image.empty();
  if (textured) {
    // The sprite through the map: each triangle of the rest shape's triangulation is
    // mapped affinely from its texels to the images of its corners (clipped without
    // anti-aliasing, so neighbours meet without seams; the outline is stroked over it).
    const SceneTexture& t = *extras.texture;
    TriangulateOptions to;
    to.max_edge = edge_for_vertex_count(shape, 1500);
    const TriMesh mesh = triangulate(shape, to);
    const VectorXcd fm = evaluate_map(evaluate_basis(cage, mesh.vertices, kBasisC), map).f;
    const auto tex = texture_surface(t.image);
    cairo_save(cr);
    cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
    for (const auto& tri : mesh.triangles) {
      cd s[3], q[3];
      for (int k = 0; k < 3; ++k) {
        const size_t v = static_cast<size_t>(tri[static_cast<size_t>(k)]);
        s[k] = texel_of(t, mesh.vertices[v]);
        q[k] = fr.px(fm(static_cast<Eigen::Index>(v)));
      }
      // q = A s + b: A from the edge vectors.
      const cd ds1 = s[1] - s[0], ds2 = s[2] - s[0], dq1 = q[1] - q[0], dq2 = q[2] - q[0];
      const double det = ds1.real() * ds2.imag() - ds1.imag() * ds2.real();
      if (std::abs(det) < 1e-12) continue;
      const double i00 = ds2.imag() / det, i01 = -ds2.real() / det, i10 = -ds1.imag() / det, i11 = ds1.real() / det;
      const double a = dq1.real() * i00 + dq2.real() * i10, c = dq1.real() * i01 + dq2.real() * i11;
      const double b = dq1.imag() * i00 + dq2.imag() * i10, d = dq1.imag() * i01 + dq2.imag() * i11;
      cairo_matrix_t m;
      cairo_matrix_init(&m, a, b, c, d, q[0].real() - a * s[0].real() - c * s[0].imag(), q[0].imag() - b * s[0].real() - d * s[0].imag());
      cairo_save(cr);
      cairo_move_to(cr, q[0].real(), q[0].imag());
      cairo_line_to(cr, q[1].real(), q[1].imag());
      cairo_line_to(cr, q[2].real(), q[2].imag());
      cairo_close_path(cr);
      cairo_clip(cr);
      cairo_transform(cr, &m);
      set_texture_source(cr, tex.get(), t.filter);
      cairo_paint(cr);
      cairo_restore(cr);
    }
    cairo_restore(cr);
  }
  // Overlapping layers fill by winding (even-odd would punch the overlap out as a hole).
  cairo_set_fill_rule(cr, extras.overlaps ? CAIRO_FILL_RULE_WINDING : CAIRO_FILL_RULE_EVEN_ODD);
  size_t off = 0;
  for (int l = 0; l < shape.loop_count(); ++l) {
    const size_t n = static_cast<size_t>(dense.loop_begin[static_cast<size_t>(l) + 1] - dense.loop_begin[static_cast<size_t>(l)]);
    Loop img(n);
    for (size_t i = 0; i < n; ++i) img[i] = f(static_cast<Eigen::Index>(off + i));
    off += n;
    path(cr, fr, img);
  }
  if (extras.uncertified)
    cairo_set_source_rgba(cr, 0.98, 0.72, 0.72, textured ? 0.45 : 1.0);
  else
    cairo_set_source_rgba(cr, 0.85, 0.9, 0.97, textured ? 0.0 : 1.0);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.12, 0.25, 0.5);
  cairo_set_line_width(cr, 1.6);
  cairo_stroke(cr);
  cairo_set_source_rgba(cr, 0.2, 0.35, 0.6, 0.55);
  cairo_set_line_width(cr, 0.8);
  for (const auto& l : lines) {
    for (size_t i = 0; i < l.size(); ++i) {
      const cd q = fr.px(f(static_cast<Eigen::Index>(off + i)));
      if (i == 0)
        cairo_move_to(cr, q.real(), q.imag());
      else
        cairo_line_to(cr, q.real(), q.imag());
    }
    off += l.size();
    cairo_stroke(cr);
  }
  cairo_set_line_width(cr, 2);
  for (const cd& t : extras.targets) {
    const cd q = fr.px(t);
    cairo_set_source_rgb(cr, 0.9, 0.5, 0.0);
    cairo_arc(cr, q.real(), q.imag(), 6, 0, 2 * M_PI);
    cairo_stroke(cr);
  }
  for (const cd& h : extras.handles_image) {
    const cd q = fr.px(h);
    cairo_set_source_rgb(cr, 0.8, 0.1, 0.1);
    cairo_arc(cr, q.real(), q.imag(), 3.5, 0, 2 * M_PI);
    cairo_fill(cr);
  }
  if (extras.overlaps) {  // amber, distinct from the uncertified red
    cairo_set_source_rgb(cr, 0.95, 0.55, 0.0);
    cairo_set_line_width(cr, 6);
    cairo_rectangle(cr, 3, 3, width_px - 6, height_px - 6);
    cairo_stroke(cr);
  }
  if (!extras.title.empty() || extras.uncertified || extras.overlaps || extras.not_converged) {
    cairo_set_source_rgb(cr, extras.uncertified ? 0.8 : 0.1, 0.1, 0.1);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 14);
    cairo_move_to(cr, pad, 18);
    const std::string t = extras.title + (extras.uncertified ? "  [NOT CERTIFIED]" : "");
    cairo_show_text(cr, t.c_str());
    if (extras.overlaps) {
      cairo_set_source_rgb(cr, 0.85, 0.45, 0.0);
      cairo_show_text(cr, "  [OVERLAPS ITSELF]");
    }
    if (extras.not_converged) {
      cairo_set_source_rgb(cr, 0.9, 0.45, 0.0);
      cairo_show_text(cr, "  [NOT CONVERGED]");
    }
  }
  canvas.write(png);
}

}  // namespace hsi::draw

namespace hsi::draw {

void plot_series(const std::filesystem::path& png, const std::string& title, const std::string& xlabel,
                 const std::vector<double>& x, const std::vector<Series>& series, const std::vector<double>& flagged,
                 int W, int H) {
  PlotSpec spec;
  spec.title = title;
  spec.xlabel = xlabel;
  spec.x = x;
  spec.series = series;
  spec.flagged = flagged;
  spec.width_px = W;
  spec.height_px = H;
  plot_series(png, spec);
}

namespace {
// Tick values of a linear axis over [lo, hi]: multiples of 1, 2 or 5 × 10^k, about `target` of them.
std::vector<double> linear_ticks(double lo, double hi, int target) {
  const double raw = (hi - lo) / std::max(1, target);
  const double base = std::pow(10.0, std::floor(std::log10(raw)));
  double step = base;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * base >= raw) {
      step = m * base;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) t.push_back(std::abs(v) < 1e-12 * step ? 0 : v);
  return t;
}
// A log axis over [lo, hi] (lo > 0): decades, with 2 and 5 between them when there are few decades.
std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> t;
  const int d0 = static_cast<int>(std::floor(std::log10(lo))), d1 = static_cast<int>(std::ceil(std::log10(hi)));
  const bool fine = d1 - d0 <= 3;
  for (int d = d0; d <= d1; ++d)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1 && !fine) continue;
      const double v = m * std::pow(10.0, d);
      if (v >= lo * (1 - 1e-12) && v <= hi * (1 + 1e-12)) t.push_back(v);
    }
  if (t.size() < 2) return {lo, hi};
  return t;
}
}  // namespace

void plot_series(const std::filesystem::path& png, const PlotSpec& spec) {
  const int W = spec.width_px, H = spec.height_px;
  const std::vector<double>& x = spec.x;
  const Canvas canvas(W, H);
  cairo_t* cr = canvas.cr();
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

  // Legend rows: as many entries per row as fit between the margins.
  cairo_set_font_size(cr, 11);
  const double L = spec.ylabel.empty() ? 70 : 86, R = 20, B = 48;
  // Entries past the series: the kinds of vertical marks present (index series.size():
  // flagged, red; series.size() + 1: unconverged, orange).
  std::vector<std::vector<size_t>> rows(1);
  double row_w = 0;
  const size_t S = spec.series.size();
  auto entry_name = [&](size_t k) -> const std::string& {
    return k < S ? spec.series[k].name : k == S ? spec.flagged_label : spec.unconverged_label;
  };
  std::vector<size_t> entries;
  for (size_t k = 0; k < S; ++k) entries.push_back(k);
  if (!spec.flagged.empty()) entries.push_back(S);
  if (!spec.unconverged.empty()) entries.push_back(S + 1);
  std::vector<double> entry_w(S + 2);
  for (size_t k : entries) {
    cairo_text_extents_t ext;
    cairo_text_extents(cr, entry_name(k).c_str(), &ext);
    entry_w[k] = ext.x_advance + 40;
    if (!rows.back().empty() && row_w + entry_w[k] > W - L - R) {
      rows.emplace_back();
      row_w = 0;
    }
    rows.back().push_back(k);
    row_w += entry_w[k];
  }
  const double legend_top = 34, row_h = 17;
  const double note_h = spec.note.empty() ? 0 : 15;
  const double T = legend_top + row_h * static_cast<double>(rows.size()) + note_h + 6;

  double x0 = x.empty() ? 0 : x.front(), x1 = x.empty() ? 1 : x.back();
  if (x1 <= x0) x1 = x0 + 1;
  double y0 = std::numeric_limits<double>::infinity(), y1 = -y0, pos_lo = y0;
  bool any_infinite = false;
  for (const Series& s : spec.series)
    for (double v : s.y) {
      if (std::isfinite(v)) {
        y0 = std::min(y0, v);
        y1 = std::max(y1, v);
        if (v > 0) pos_lo = std::min(pos_lo, v);
      } else if (v > 0) {
        any_infinite = true;
      }
    }
  if (!std::isfinite(y0)) y0 = 0, y1 = 1;
  bool log_y = spec.y_scale == AxisScale::kLog || (spec.y_scale == AxisScale::kAuto && y0 > 0 && y1 / y0 > 20);
  if (log_y && !(y0 > 0)) log_y = false;  // nothing positive to draw on a log axis
  std::vector<double> ticks;
  if (log_y) {
    y0 /= 1.15;
    y1 *= 1.15;
    ticks = log_ticks(y0, y1);
  } else {
    if (y1 - y0 < 1e-12 * std::max(1.0, std::abs(y1))) {
      y0 -= 0.5 * std::max(1e-6, std::abs(y0) * 1e-3);
      y1 += 0.5 * std::max(1e-6, std::abs(y1) * 1e-3);
    }
    const double pad = 0.05 * (y1 - y0);
    y0 -= pad;
    y1 += pad;
    ticks = linear_ticks(y0, y1, 5);
  }
  const double top_band = any_infinite ? 12 : 0;  // markers for +inf sit in a band above the data
  auto px = [&](double xv) { return L + (xv - x0) / (x1 - x0) * (W - L - R); };
  auto py = [&](double yv) {
    const double u = log_y ? (std::log(yv) - std::log(y0)) / (std::log(y1) - std::log(y0)) : (yv - y0) / (y1 - y0);
    return H - B - u * (H - T - B - top_band);
  };
  cairo_set_font_size(cr, 11);
  cairo_set_line_width(cr, 1);
  char buf[64];
  for (double yv : ticks) {
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, L, py(yv));
    cairo_line_to(cr, W - R, py(yv));
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    std::snprintf(buf, sizeof buf, "%.4g", yv);
    cairo_text_extents_t ext;
    cairo_text_extents(cr, buf, &ext);
    cairo_move_to(cr, L - 6 - ext.x_advance, py(yv) + 4);
    cairo_show_text(cr, buf);
  }
  for (double xv : linear_ticks(x0, x1, 6)) {
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, px(xv), T);
    cairo_line_to(cr, px(xv), H - B);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    std::snprintf(buf, sizeof buf, "%.3g", xv);
    cairo_text_extents_t ext;
    cairo_text_extents(cr, buf, &ext);
    cairo_move_to(cr, px(xv) - ext.x_advance / 2, H - B + 16);
    cairo_show_text(cr, buf);
  }
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_rectangle(cr, L, T, W - L - R, H - T - B);
  cairo_stroke(cr);
  {
    cairo_text_extents_t ext;
    cairo_text_extents(cr, spec.xlabel.c_str(), &ext);
    cairo_move_to(cr, L + (W - L - R - ext.x_advance) / 2, H - 12);
    cairo_show_text(cr, spec.xlabel.c_str());
  }
  if (!spec.ylabel.empty()) {
    const std::string label = spec.ylabel + (log_y ? " (log scale)" : "");
    cairo_text_extents_t ext;
    cairo_text_extents(cr, label.c_str(), &ext);
    cairo_save(cr);
    cairo_move_to(cr, 16, T + (H - T - B + ext.x_advance) / 2);
    cairo_rotate(cr, -M_PI / 2);
    cairo_show_text(cr, label.c_str());
    cairo_restore(cr);
  }
  cairo_set_font_size(cr, 14);
  cairo_move_to(cr, L, 22);
  cairo_show_text(cr, spec.title.c_str());
  cairo_set_font_size(cr, 11);
  const double d[] = {5.0, 3.0};
  const double mark_dash[] = {4.0, 2.0};
  for (size_t r = 0; r < rows.size(); ++r) {
    double lx = L;
    const double ly = legend_top + row_h * static_cast<double>(r) + 6;
    for (size_t k : rows[r]) {
      if (k < S) {
        const Series& s = spec.series[k];
        cairo_set_source_rgb(cr, s.r, s.g, s.b);
        cairo_set_dash(cr, d, s.dashed ? 2 : 0, 0);
        cairo_set_line_width(cr, std::max(2.0, s.width));
        cairo_move_to(cr, lx, ly - 4);
        cairo_line_to(cr, lx + 26, ly - 4);
        cairo_stroke(cr);
      } else {  // a short vertical mark, as drawn on the plot
        if (k == S)
          cairo_set_source_rgb(cr, 0.85, 0.05, 0.05);
        else
          cairo_set_source_rgb(cr, 0.95, 0.5, 0.0);
        cairo_set_dash(cr, mark_dash, k == S ? 0 : 2, 0);
        cairo_set_line_width(cr, 2);
        cairo_move_to(cr, lx + 13, ly - 11);
        cairo_line_to(cr, lx + 13, ly + 3);
        cairo_stroke(cr);
      }
      cairo_set_dash(cr, nullptr, 0, 0);
      cairo_move_to(cr, lx + 32, ly);
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      cairo_show_text(cr, entry_name(k).c_str());
      lx += entry_w[k];
    }
  }
  if (!spec.note.empty()) {
    cairo_set_font_size(cr, 10);
    cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
    cairo_move_to(cr, L, legend_top + row_h * static_cast<double>(rows.size()) + 4);
    cairo_show_text(cr, spec.note.c_str());
    cairo_set_font_size(cr, 11);
  }
  cairo_save(cr);
  cairo_rectangle(cr, L, T, W - L - R, H - T - B);
  cairo_clip(cr);
  const double dot[] = {1.5, 3.0};
  cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
  cairo_set_line_width(cr, 1);
  cairo_set_dash(cr, dot, 2, 0);
  // A vertical line across the plot at each x, in the current source, width and dash.
  auto vertical_lines = [&](const std::vector<double>& xs) {
    for (double xv : xs) {
      cairo_move_to(cr, px(xv), T);
      cairo_line_to(cr, px(xv), H - B);
      cairo_stroke(cr);
    }
  };
  vertical_lines(spec.x_marks);
  cairo_set_dash(cr, nullptr, 0, 0);
  for (const Series& s : spec.series) {
    cairo_set_source_rgb(cr, s.r, s.g, s.b);
    cairo_set_dash(cr, d, s.dashed ? 2 : 0, 0);
    cairo_set_line_width(cr, s.width);
    bool pen = false;
    const size_t n = std::min(x.size(), s.y.size());
    for (size_t i = 0; i < n; ++i) {
      const double v = s.y[i];
      if (!std::isfinite(v) || (log_y && v <= 0)) {
        if (pen) cairo_stroke(cr);
        pen = false;
        continue;
      }
      if (!pen)
        cairo_move_to(cr, px(x[i]), py(v));
      else
        cairo_line_to(cr, px(x[i]), py(v));
      if (s.steps && i + 1 < n) cairo_line_to(cr, px(x[i + 1]), py(v));
      pen = true;
    }
    if (pen) cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    for (size_t i = 0; i < n; ++i)
      if (std::isinf(s.y[i]) && s.y[i] > 0) {  // a triangle pointing up at the top of the plot
        const double cx = px(x[i]), cy = T + 2;
        cairo_move_to(cr, cx, cy);
        cairo_line_to(cr, cx - 4, cy + 8);
        cairo_line_to(cr, cx + 4, cy + 8);
        cairo_close_path(cr);
        cairo_fill(cr);
      }
  }
  cairo_set_source_rgb(cr, 0.85, 0.05, 0.05);
  cairo_set_line_width(cr, 2);
  vertical_lines(spec.flagged);
  // Not converged: orange, dashed, so that a frame both uncertified and unconverged
  // shows both colours.
  cairo_set_source_rgb(cr, 0.95, 0.5, 0.0);
  cairo_set_dash(cr, mark_dash, 2, 0);
  vertical_lines(spec.unconverged);
  cairo_set_dash(cr, nullptr, 0, 0);
  cairo_restore(cr);
  canvas.write(png);
}

}  // namespace hsi::draw
