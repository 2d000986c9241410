// Straight-alpha RGBA (png.h's RgbaImage) into a cairo ARGB32 surface of its size
// (premultiplied, native-endian words): the one conversion plot.cpp and raster.cpp share.
#pragma once

#include <cairo.h>

#include <cstddef>
#include <cstdint>

#include "hsi/png.h"

namespace hsi::draw::detail {

inline void write_premultiplied(const RgbaImage& img, cairo_surface_t* s) {
  cairo_surface_flush(s);
  unsigned char* data = cairo_image_surface_get_data(s);
  const int stride = cairo_image_surface_get_stride(s);
  for (int y = 0; y < img.height; ++y) {
    auto* row = reinterpret_cast<uint32_t*>(data + static_cast<ptrdiff_t>(y) * stride);
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* p = img.at(x, y);
      const uint32_t a = p[3];
      auto pre = [a](uint32_t c) { return (c * a + 127) / 255; };
      row[x] = (a << 24) | (pre(p[0]) << 16) | (pre(p[1]) << 8) | pre(p[2]);
    }
  }
  cairo_surface_mark_dirty(s);
}

}  // namespace hsi::draw::detail
