// hsi_png_probe FILE R G B [TOLERANCE] [X0 X1]: prints how many pixels of the PNG are
// within TOLERANCE (0-255, default 40, per channel) of the colour R G B, counting only
// columns X0..X1 when given. The CLI tests use it to see marks in plots.
#include <cairo.h>

#include <cstdio>
#include <cstdlib>
#include <cstdint>

int main(int argc, char** argv) {
  if (argc != 5 && argc != 6 && argc != 8) {
    std::fprintf(stderr, "usage: hsi_png_probe FILE R G B [TOLERANCE] [X0 X1]\n");
    return 2;
  }
  cairo_surface_t* s = cairo_image_surface_create_from_png(argv[1]);
  if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
    std::fprintf(stderr, "hsi_png_probe: cannot read %s\n", argv[1]);
    return 2;
  }
  const int want[3] = {std::atoi(argv[2]), std::atoi(argv[3]), std::atoi(argv[4])};
  const int tol = argc >= 6 ? std::atoi(argv[5]) : 40;
  const int w = cairo_image_surface_get_width(s), h = cairo_image_surface_get_height(s);
  const int x0 = argc == 8 ? std::atoi(argv[6]) : 0, x1 = argc == 8 ? std::atoi(argv[7]) : w - 1;
  const int stride = cairo_image_surface_get_stride(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  long count = 0;
  for (int y = 0; y < h; ++y)
    for (int x = x0; x <= x1 && x < w; ++x) {
      uint32_t px;
      __builtin_memcpy(&px, data + y * stride + 4 * x, 4);  // ARGB32, native endian
      const int c[3] = {static_cast<int>((px >> 16) & 255), static_cast<int>((px >> 8) & 255), static_cast<int>(px & 255)};
      bool ok = true;
      for (int k = 0; k < 3; ++k) ok = ok && std::abs(c[k] - want[k]) <= tol;
      count += ok;
    }
  cairo_surface_destroy(s);
  std::printf("%ld\n", count);
  return 0;
}
