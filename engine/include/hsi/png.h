// PNG files, read and written in one place (libpng's simplified API, which converts
// every colour type and bit depth): RGBA8 images for textures, rendered frames and
// screenshots, the alpha channel for import-png (png_import.h), and the texture check
// of glTF export. Straight (not premultiplied) alpha, 8 bits per channel, rows from
// the top of the image down. Every error is an InputError naming the file.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace hsi {

struct RgbaImage {
  int width = 0, height = 0;
  std::vector<uint8_t> pixels;  // width × height × 4 bytes: R, G, B, A

  RgbaImage() = default;
  RgbaImage(int w, int h, std::array<uint8_t, 4> fill = {0, 0, 0, 0});
  bool empty() const { return width <= 0 || height <= 0; }
  uint8_t* at(int x, int y) { return pixels.data() + (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4; }
  const uint8_t* at(int x, int y) const {
    return pixels.data() + (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4;
  }
};

// Largest accepted image side, in pixels.
inline constexpr int kPngMaxSide = 16384;

// Reads any PNG (grey, palette, RGB, with or without alpha, 8 or 16 bits) as RGBA8.
// Throws InputError naming the file: missing, not a PNG, corrupt, too large.
RgbaImage read_png(const std::filesystem::path& path);
// The same from the file's bytes in memory; `name` is used in messages.
RgbaImage decode_png(std::span<const unsigned char> png_bytes, const std::string& name);
// Writes an RGBA8 PNG atomically (temporary file, then rename). Throws InputError.
void write_png(const std::filesystem::path& path, const RgbaImage& image);

// The alpha channel alone, at the source's precision (what import-png traces).
struct PngAlpha {
  int width = 0, height = 0;
  std::vector<uint16_t> alpha;  // row-major, row 0 at the top
  double max_value = 255;       // 255 for 8-bit sources, 65535 for 16-bit ones
  std::vector<std::string> warnings;  // libpng's, if any
};
// Throws InputError as read_png does, and for an image without an alpha channel
// (RGB, grey, or a palette without a tRNS chunk).
PngAlpha decode_png_alpha(std::span<const unsigned char> png_bytes, const std::string& name);

// A file's bytes for the decoders above. Throws InputError naming `name`: no such
// file, a directory, unreadable.
std::vector<unsigned char> read_png_bytes(const std::filesystem::path& path, const std::string& name);

// Decodes a whole PNG (any colour type and depth) to check that it is a usable
// texture, and returns its {width, height}. Throws InputError naming `name` and the
// problem: not a PNG, corrupt or truncated data, an empty or too large image.
std::array<int, 2> check_png_texture(std::span<const unsigned char> png_bytes, const std::string& name);

// Refuses, before anything is allocated for the pixels, a PNG whose header claims
// more pixels than its compressed data could hold (deflate expands at most ~1032:1):
// a truncated or corrupt file that would otherwise cost up to gigabytes of memory
// before libpng finds the data missing. Throws InputError naming `name`, the size
// claimed and the data present. Call after the signature is known to be PNG's.
// (The readers above call it.)
void check_png_payload(std::span<const unsigned char> png_bytes, const std::string& name);

}  // namespace hsi
