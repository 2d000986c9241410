// A scene's texture or the checkerboard in its place (see scene_texture.h).
#include "hsi/scene_texture.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace hsi {

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
  t.filter = scene.texture_filter;
  return t;
}

}  // namespace hsi
