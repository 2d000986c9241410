// RGBA images for offscreen rendering: the renderer's textures and results, read
// and written as PNG (libpng). Straight (not premultiplied) alpha, 8 bits per
// channel, rows from the top of the image down.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "hsi/domain.h"
#include "hsi/scene_io.h"

namespace hsi::vk {

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

// Reads any PNG (grey, palette, RGB, with or without alpha, 8 or 16 bits) as RGBA8.
// Throws hsi::InputError naming the file: missing, not a PNG, corrupt, too large.
RgbaImage read_png(const std::filesystem::path& path);
// Writes an RGBA8 PNG atomically (temporary file, then rename). Throws InputError.
void write_png(const std::filesystem::path& path, const RgbaImage& image);

// A checkerboard over a rest shape's bounding box (16 square checks along the longer
// side, 32 pixels each), the texture for a scene without one: it still shows how the
// map deforms the shape. Sets `rect` to the world rectangle [x0, y0, x1, y1] it
// covers. grid_lines: dark lines along the checks' edges (hsi render) or plain (viewer).
RgbaImage checker_texture(const BoundingBox& box, std::array<double, 4>& rect, bool grid_lines = true);

// What a scene is drawn with: its texture (the PNG it names, over texture_rect or the
// shape's bounding box), or a checkerboard (checker_texture over the shape's bounding
// box) where it has none or `use_checker` asks for one.
struct SceneTexture {
  RgbaImage image;
  std::array<double, 4> rect{};
  bool checker = false;  // the checkerboard
};
// Throws InputError naming `scene_file` and the texture file when that file is
// missing (read_png's errors when it is broken); `alternative` ("render with
// --no-texture") is offered in the message besides fixing the scene.
SceneTexture scene_texture(const Scene& scene, const std::string& scene_file, bool use_checker = false,
                           bool grid_lines = true, const std::string& alternative = "");

}  // namespace hsi::vk
