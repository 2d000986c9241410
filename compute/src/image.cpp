// PNG reading and writing through libpng's simplified API (png_image), which
// converts every PNG colour type and bit depth to RGBA8.
#include "hsi/compute/image.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "hsi/domain.h"
#include "hsi/png_import.h"

namespace hsi::vk {

namespace {
constexpr int kMaxSide = 16384;
}

RgbaImage::RgbaImage(int w, int h, std::array<uint8_t, 4> fill) : width(w), height(h) {
  if (w < 0 || h < 0) throw InputError("image: negative size " + std::to_string(w) + " x " + std::to_string(h));
  pixels.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
  for (size_t i = 0; i < pixels.size(); i += 4) std::memcpy(&pixels[i], fill.data(), 4);
}

RgbaImage read_png(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the image (missing or unreadable)");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&img, bytes.data(), bytes.size()))
    throw InputError(path.string() + ": not a readable PNG (" + img.message + ")");
  if (img.width == 0 || img.height == 0 || img.width > kMaxSide || img.height > kMaxSide) {
    png_image_free(&img);
    throw InputError(path.string() + ": image size " + std::to_string(img.width) + " x " +
                     std::to_string(img.height) + " is outside 1.." + std::to_string(kMaxSide));
  }
  try {
    check_png_payload({reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()}, path.string());
  } catch (const InputError&) {
    png_image_free(&img);
    throw;
  }
  img.format = PNG_FORMAT_RGBA;
  RgbaImage out(static_cast<int>(img.width), static_cast<int>(img.height));
  if (!png_image_finish_read(&img, nullptr, out.pixels.data(), 0, nullptr))
    throw InputError(path.string() + ": corrupt or truncated PNG (" + img.message + ")");
  return out;
}

void write_png(const std::filesystem::path& path, const RgbaImage& image) {
  if (image.empty() || image.pixels.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 4)
    throw InputError(path.string() + ": cannot write an empty or inconsistent image");
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  img.width = static_cast<png_uint_32>(image.width);
  img.height = static_cast<png_uint_32>(image.height);
  img.format = PNG_FORMAT_RGBA;
  png_alloc_size_t size = 0;
  if (!png_image_write_get_memory_size(img, size, 0, image.pixels.data(), 0, nullptr))
    throw InputError(path.string() + ": PNG encoding failed (" + img.message + ")");
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&img, bytes.data(), &size, 0, image.pixels.data(), 0, nullptr))
    throw InputError(path.string() + ": PNG encoding failed (" + img.message + ")");
  bytes.resize(size);
  write_file_atomic(path, bytes);
}

RgbaImage checker_texture(const BoundingBox& box, std::array<double, 4>& rect, bool grid_lines) {
  const cd ext = box.hi - box.lo;
  const double side = std::max(ext.real(), ext.imag());
  constexpr int kChecks = 16, kPx = 32;
  const int w = std::max(1, static_cast<int>(std::ceil(ext.real() / side * kChecks))) * kPx;
  const int h = std::max(1, static_cast<int>(std::ceil(ext.imag() / side * kChecks))) * kPx;
  rect = {box.lo.real(), box.hi.imag() - h / static_cast<double>(kPx) * side / kChecks,
          box.lo.real() + w / static_cast<double>(kPx) * side / kChecks, box.hi.imag()};
  RgbaImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool odd = ((x / kPx) + (y / kPx)) % 2;
      const bool line = grid_lines && (x % kPx == 0 || y % kPx == 0);
      const uint8_t v[4] = {static_cast<uint8_t>(line ? 70 : odd ? 232 : 180),
                            static_cast<uint8_t>(line ? 80 : odd ? 214 : 196),
                            static_cast<uint8_t>(line ? 110 : odd ? 178 : 228), 255};
      std::copy(v, v + 4, img.at(x, y));
    }
  return img;
}

SceneTexture scene_texture(const Scene& scene, const std::string& scene_file, bool use_checker, bool grid_lines,
                           const std::string& alternative) {
  SceneTexture t;
  if (use_checker || scene.texture.empty()) {
    t.image = checker_texture(bounding_box(scene.shape), t.rect, grid_lines);
    t.checker = true;
    return t;
  }
  const std::filesystem::path path = scene.texture_path();
  if (!std::filesystem::exists(path))
    throw InputError(scene_file + ": the texture file " + path.string() + " does not exist (fix \"texture\" in the scene" +
                     (alternative.empty() ? "" : ", or " + alternative) + ")");
  t.image = read_png(path);
  t.rect = scene.texture_rect_or_bounds();
  return t;
}

}  // namespace hsi::vk
