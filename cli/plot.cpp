// Cairo drawings for diagnostics; kept out of engine/ (which depends on Eigen only).
#include "plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
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
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surf(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width_px, height_px), cairo_surface_destroy);
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> ctx(cairo_create(surf.get()), cairo_destroy);
  cairo_t* cr = ctx.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
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
  cairo_surface_flush(surf.get());
  if (cairo_surface_write_to_png(surf.get(), png.string().c_str()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write " + png.string());
}

}  // namespace hsi::cli
