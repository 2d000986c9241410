// Cairo drawings for diagnostics; kept out of engine/ (which depends on Eigen only).
#include "plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace hsi::cli {
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
               int width_px) {
  BoundingBox bb = bounding_box(cage.loops.front());
  const double pad = 20;
  const double sx = bb.hi.real() - bb.lo.real(), sy = bb.hi.imag() - bb.lo.imag();
  const double scale = (width_px - 2 * pad) / std::max(sx, 1e-300);
  const int height_px = static_cast<int>(std::ceil(sy * scale + 2 * pad));
  const Frame f{bb.lo, scale, width_px, height_px, pad};
  const Canvas canvas(width_px, height_px);
  cairo_t* cr = canvas.cr();
  // Shape, filled with holes cut out (even-odd).
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
  for (int k = 0; k < shape.loop_count(); ++k) path(cr, f, shape.loop(k));
  cairo_set_source_rgb(cr, 0.78, 0.86, 0.95);
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

}  // namespace hsi::cli

namespace hsi::cli {

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
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
  size_t off = 0;
  for (int l = 0; l < shape.loop_count(); ++l) {
    const size_t n = static_cast<size_t>(dense.loop_begin[static_cast<size_t>(l) + 1] - dense.loop_begin[static_cast<size_t>(l)]);
    Loop img(n);
    for (size_t i = 0; i < n; ++i) img[i] = f(static_cast<Eigen::Index>(off + i));
    off += n;
    path(cr, fr, img);
  }
  if (extras.uncertified)
    cairo_set_source_rgb(cr, 0.98, 0.72, 0.72);
  else
    cairo_set_source_rgb(cr, 0.85, 0.9, 0.97);
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
  if (!extras.title.empty() || extras.uncertified) {
    cairo_set_source_rgb(cr, extras.uncertified ? 0.8 : 0.1, 0.1, 0.1);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 14);
    cairo_move_to(cr, pad, 18);
    const std::string t = extras.title + (extras.uncertified ? "  [NOT CERTIFIED]" : "");
    cairo_show_text(cr, t.c_str());
  }
  canvas.write(png);
}

}  // namespace hsi::cli

namespace hsi::cli {

void plot_series(const std::filesystem::path& png, const std::string& title, const std::string& xlabel,
                 const std::vector<double>& x, const std::vector<Series>& series, const std::vector<double>& flagged,
                 int W, int H) {
  const Canvas canvas(W, H);
  cairo_t* cr = canvas.cr();
  const double L = 70, R = 20, T = 54, B = 48;  // title on the first line, legend on the second
  double x0 = x.empty() ? 0 : x.front(), x1 = x.empty() ? 1 : x.back();
  if (x1 <= x0) x1 = x0 + 1;
  double y0 = std::numeric_limits<double>::infinity(), y1 = -y0;
  for (const Series& s : series)
    for (double v : s.y)
      if (std::isfinite(v)) {
        y0 = std::min(y0, v);
        y1 = std::max(y1, v);
      }
  if (!std::isfinite(y0)) y0 = 0, y1 = 1;
  if (y1 - y0 < 1e-12 * std::max(1.0, std::abs(y1))) {
    y0 -= 0.5 * std::max(1e-6, std::abs(y0) * 1e-3);
    y1 += 0.5 * std::max(1e-6, std::abs(y1) * 1e-3);
  }
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad;
  y1 += pad;
  auto px = [&](double xv) { return L + (xv - x0) / (x1 - x0) * (W - L - R); };
  auto py = [&](double yv) { return H - B - (yv - y0) / (y1 - y0) * (H - T - B); };
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 11);
  cairo_set_line_width(cr, 1);
  char buf[64];
  for (int i = 0; i <= 5; ++i) {  // grid and ticks
    const double yv = y0 + (y1 - y0) * i / 5, xv = x0 + (x1 - x0) * i / 5;
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, L, py(yv));
    cairo_line_to(cr, W - R, py(yv));
    cairo_move_to(cr, px(xv), T);
    cairo_line_to(cr, px(xv), H - B);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    std::snprintf(buf, sizeof buf, "%.4g", yv);
    cairo_move_to(cr, 6, py(yv) + 4);
    cairo_show_text(cr, buf);
    std::snprintf(buf, sizeof buf, "%.3g", xv);
    cairo_move_to(cr, px(xv) - 10, H - B + 16);
    cairo_show_text(cr, buf);
  }
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_rectangle(cr, L, T, W - L - R, H - T - B);
  cairo_stroke(cr);
  cairo_move_to(cr, W / 2.0 - 20, H - 10);
  cairo_show_text(cr, xlabel.c_str());
  cairo_set_font_size(cr, 14);
  cairo_move_to(cr, L, 22);
  cairo_show_text(cr, title.c_str());
  cairo_set_font_size(cr, 11);
  double legend_x = W - R - 10;
  for (size_t k = series.size(); k-- > 0;) {
    const Series& s = series[k];
    cairo_text_extents_t ext;
    cairo_text_extents(cr, s.name.c_str(), &ext);
    legend_x -= ext.x_advance + 34;
    cairo_set_source_rgb(cr, s.r, s.g, s.b);
    const double d[] = {5.0, 3.0};
    cairo_set_dash(cr, d, s.dashed ? 2 : 0, 0);
    cairo_set_line_width(cr, 2);
    cairo_move_to(cr, legend_x, 40 - 4);
    cairo_line_to(cr, legend_x + 22, 40 - 4);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_move_to(cr, legend_x + 26, 40);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_show_text(cr, s.name.c_str());
  }
  cairo_rectangle(cr, L, T, W - L - R, H - T - B);
  cairo_clip(cr);
  for (const Series& s : series) {
    cairo_set_source_rgb(cr, s.r, s.g, s.b);
    const double d[] = {5.0, 3.0};
    cairo_set_dash(cr, d, s.dashed ? 2 : 0, 0);
    cairo_set_line_width(cr, 1.6);
    bool pen = false;
    for (size_t i = 0; i < x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.y[i])) {
        pen = false;
        continue;
      }
      if (!pen)
        cairo_move_to(cr, px(x[i]), py(s.y[i]));
      else
        cairo_line_to(cr, px(x[i]), py(s.y[i]));
      pen = true;
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
  }
  cairo_set_source_rgb(cr, 0.85, 0.05, 0.05);
  cairo_set_line_width(cr, 2);
  for (double f : flagged) {
    cairo_move_to(cr, px(f), T);
    cairo_line_to(cr, px(f), H - B);
    cairo_stroke(cr);
  }
  canvas.write(png);
}

}  // namespace hsi::cli
