// Compositing rendered frames with cairo (hsi render, hsi compare): cairo surfaces
// from the renderer's RGBA images, PNG output, text with a halo, the distortion
// colour bar. Kept out of compute/ so that it stays free of text. (The checkerboard
// for scenes without a texture is checker_texture, hsi/scene_texture.h.)
#pragma once

#include <cairo.h>

#include <array>
#include <filesystem>
#include <memory>
#include <string>

#include "hsi/domain.h"
#include "hsi/png.h"

namespace hsi::draw {

// A cairo image surface (premultiplied ARGB32) with its drawing context.
struct Surface {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surf{nullptr, cairo_surface_destroy};
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> ctx{nullptr, cairo_destroy};
  cairo_t* cr() const { return ctx.get(); }
};
Surface make_surface(int w, int h);             // transparent; throws if cairo cannot allocate it
Surface surface_from(const RgbaImage& img);  // straight-alpha RGBA in
// PNG, written atomically (a failed write leaves nothing behind).
void write_surface(const Surface& s, const std::filesystem::path& png);

// Text at baseline (x, y) in DejaVu Sans; halo: a white outline that keeps it legible over any image.
void text(cairo_t* cr, double x, double y, const std::string& s, double size, bool bold, double r, double g, double b,
          bool halo = true);
double text_width(cairo_t* cr, const std::string& s, double size, bool bold);
std::string fmt(const char* f, double v);  // snprintf of one number

// The colour bar of the distortion overlay over [lo, hi] with its caption, centred in
// the band of height `area` at the bottom of a W × H image.
void draw_legend(cairo_t* cr, int W, int H, double area, double lo, double hi, double font);

}  // namespace hsi::draw
