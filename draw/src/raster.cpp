// Cairo compositing for rendered frames (raster.h).
#include "hsi/draw/raster.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "hsi/compute/renderer.h"
#include "rgba_surface.h"

namespace hsi::draw {

Surface make_surface(int w, int h) {
  Surface s;
  s.surf.reset(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h));
  if (cairo_surface_status(s.surf.get()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cairo: cannot create a " + std::to_string(w) + " x " + std::to_string(h) + " image");
  s.ctx.reset(cairo_create(s.surf.get()));
  return s;
}

Surface surface_from(const RgbaImage& img) {
  Surface s = make_surface(img.width, img.height);
  detail::write_premultiplied(img, s.surf.get());
  return s;
}

void write_surface(const Surface& s, const std::filesystem::path& png) {
  cairo_surface_flush(s.surf.get());
  std::string bytes;
  const auto sink = [](void* closure, const unsigned char* data, unsigned int length) {
    static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
    return CAIRO_STATUS_SUCCESS;
  };
  if (cairo_surface_write_to_png_stream(s.surf.get(), sink, &bytes) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cairo: cannot encode " + png.string());
  write_file_atomic(png, bytes);
}

void text(cairo_t* cr, double x, double y, const std::string& s, double size, bool bold, double r, double g, double b,
          bool halo) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_move_to(cr, x, y);
  if (halo) {  // a white outline keeps the text legible over any texture
    cairo_text_path(cr, s.c_str());
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_set_line_width(cr, std::max(2.0, size / 5));
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_stroke(cr);
    cairo_move_to(cr, x, y);
  }
  cairo_set_source_rgb(cr, r, g, b);
  cairo_show_text(cr, s.c_str());
}

double text_width(cairo_t* cr, const std::string& s, double size, bool bold) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  return e.x_advance;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

void draw_legend(cairo_t* cr, int W, int H, double area, double lo, double hi, double font) {
  const std::string caption = "conformal distortion \xcf\x83\xe2\x82\x81/\xcf\x83\xe2\x82\x82";  // σ₁/σ₂
  const double caption_w = text_width(cr, caption, 0.85 * font, false);
  // The caption left of the bar where there is room, else above it.
  const bool beside = W - caption_w - 4 * font >= 10 * font;
  const double bar_w = beside ? std::min(28 * font, W - caption_w - 4 * font) : std::min(28 * font, W - 4 * font);
  const double bar_h = 0.9 * font;
  const double x0 = beside ? 0.5 * (W + caption_w + 0.8 * font - bar_w) : 0.5 * (W - bar_w);
  const double y0 = H - 0.5 * area - (beside ? 1.05 : 0.2) * font;  // bar + tick labels: 2.1 font tall
  cairo_pattern_t* grad = cairo_pattern_create_linear(x0, 0, x0 + bar_w, 0);
  for (int i = 0; i <= 32; ++i) {
    const auto c = compute::colormap(i / 32.0);
    cairo_pattern_add_color_stop_rgb(grad, i / 32.0, c[0], c[1], c[2]);
  }
  cairo_rectangle(cr, x0, y0, bar_w, bar_h);
  cairo_set_source(cr, grad);
  cairo_fill_preserve(cr);
  cairo_pattern_destroy(grad);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  const int ticks = 4;
  for (int i = 0; i <= ticks; ++i) {
    const double v = lo + (hi - lo) * i / ticks, x = x0 + bar_w * i / ticks;
    cairo_move_to(cr, x, y0 + bar_h);
    cairo_line_to(cr, x, y0 + bar_h + 0.3 * font);
    cairo_stroke(cr);
    const std::string s = fmt((hi - lo) / 4 < 0.01 ? "%.4f" : (hi - lo) / 4 < 0.1 ? "%.3f" : "%.2f", v);
    text(cr, x - 0.5 * text_width(cr, s, 0.8 * font, false), y0 + bar_h + 1.2 * font, s, 0.8 * font, false, 0.15, 0.15, 0.15);
  }
  if (beside)
    text(cr, x0 - caption_w - 0.8 * font, y0 + 0.85 * bar_h, caption, 0.85 * font, false, 0.15, 0.15, 0.15);
  else
    text(cr, 0.5 * (W - caption_w), y0 - 0.5 * font, caption, 0.85 * font, false, 0.15, 0.15, 0.15);
}

}  // namespace hsi::draw
