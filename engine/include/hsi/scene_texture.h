// What a scene is drawn with: its texture (a PNG, read by png.h) or a checkerboard,
// and the world rectangle it covers. Used by hsi render, hsi compare, the viewer and
// the C API's renderer.
#pragma once

#include <array>
#include <string>

#include "hsi/domain.h"
#include "hsi/png.h"
#include "hsi/scene_io.h"

namespace hsi {

// A checkerboard over a rest shape's bounding box (16 square checks along the longer
// side, 32 pixels each), the texture for a scene without one: it still shows how the
// map deforms the shape. Sets `rect` to the world rectangle [x0, y0, x1, y1] it
// covers. grid_lines: dark lines along the checks' edges (hsi render) or plain (viewer).
RgbaImage checker_texture(const BoundingBox& box, std::array<double, 4>& rect, bool grid_lines = true);

// The scene's texture (the PNG it names, over texture_rect or the shape's bounding
// box), or a checkerboard (checker_texture over the shape's bounding box) where it has
// none or `use_checker` asks for one.
struct SceneTexture {
  RgbaImage image;
  std::array<double, 4> rect{};
  bool checker = false;  // the checkerboard
  TextureFilter filter = TextureFilter::Linear;  // the scene's texture_filter (linear for the checkerboard)
};
// Throws InputError naming `scene_file` and the texture file when that file is
// missing (read_png's errors when it is broken); `alternative` ("render with
// --no-texture") is offered in the message besides fixing the scene.
SceneTexture scene_texture(const Scene& scene, const std::string& scene_file, bool use_checker = false,
                           bool grid_lines = true, const std::string& alternative = "");

}  // namespace hsi
