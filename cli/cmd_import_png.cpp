// hsi import-png: a sprite's alpha channel as a scene, textured with the sprite.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "hsi/keyframes.h"
#include "hsi/png_import.h"
#include "hsi/scene_io.h"

namespace hsi::cli {

namespace {

struct ImportPngOptions {
  std::filesystem::path sprite;
  std::filesystem::path output;
  PngImportOptions import;
  double max_edge = 0;  // pixels; 0: off
  std::string name;
};


void run(const ImportPngOptions& o) {
  std::error_code ec;
  if (std::filesystem::equivalent(o.sprite, o.output, ec))
    throw InputError("the output scene '" + o.output.string() + "' is the sprite itself; choose another file");
  if (!(o.max_edge >= 0) || !std::isfinite(o.max_edge))
    throw InputError("--max-edge must be >= 0 pixels (0: off), got " + std::to_string(o.max_edge));
  PngShape png = import_png_alpha(o.sprite, o.import);
  if (o.max_edge > 0) {
    const double len = o.max_edge * o.import.pixel_size;
    png.shape.outer = subdivide_edges(png.shape.outer, len);
    for (Loop& h : png.shape.holes) h = subdivide_edges(h, len);
    validate(png.shape);
  }

  Scene scene;
  scene.name = o.name.empty() ? o.sprite.stem().string() : o.name;
  scene.shape = png.shape;
  const std::filesystem::path out_abs = std::filesystem::absolute(o.output).lexically_normal();
  scene.base_dir = out_abs.parent_path();
  const std::filesystem::path sprite_abs = std::filesystem::absolute(o.sprite).lexically_normal();
  const std::filesystem::path rel = sprite_abs.lexically_relative(scene.base_dir);
  scene.texture = rel.empty() ? sprite_abs : rel;
  scene.texture_rect = png.texture_rect;
  save_scene(scene, o.output);

  const Shape& s = png.shape;
  std::printf("wrote %s: %s %dx%d px, outer loop %zu vertices", o.output.string().c_str(), o.sprite.string().c_str(),
              png.width, png.height, s.outer.size());
  if (s.holes.empty()) {
    std::printf(", no holes");
  } else {
    std::printf(", %zu hole%s (", s.holes.size(), s.holes.size() == 1 ? "" : "s");
    for (size_t i = 0; i < s.holes.size(); ++i) std::printf("%s%zu", i ? ", " : "", s.holes[i].size());
    std::printf(" vertices)");
  }
  for (const std::string& w : png.warnings) std::printf("; warning: %s", w.c_str());
  std::printf("\nnext: %s\n", kHowToAddKeyframes);
}

}  // namespace

void register_import_png(CLI::App& app) {
  auto opts = std::make_shared<ImportPngOptions>();
  CLI::App* cmd = app.add_subcommand(
      "import-png",
      "Import a sprite's alpha channel as a scene. The boundary is the iso-line of alpha at\n"
      "--threshold (marching squares with sub-pixel vertices), simplified to within\n"
      "--tolerance pixels. Transparent regions enclosed by the sprite become holes; if the\n"
      "sprite has several separate pieces, only the largest is kept (with a warning), and\n"
      "holes under --min-hole-area square pixels are dropped. The import checks that the scene\n"
      "gets a cage: holes too narrow for one (slivers) are filled, narrowest first, with a\n"
      "warning naming each. Shapes under 16 square pixels are refused. The scene is textured with the sprite: y\n"
      "points up, pixel (0,0) is the top-left corner at (0, height * pixel size), and the\n"
      "texture rectangle covers the whole image. Accepts RGBA, grey+alpha and palette\n"
      "images with transparency (tRNS), 8 or 16 bits; images without alpha are refused.");
  cmd->add_option("SPRITE", opts->sprite, "The sprite (PNG with an alpha channel)")->required();
  cmd->add_option("-o,--output", opts->output,
                  "Scene file to write (JSON); the sprite is referenced relative to its folder")
      ->required();
  cmd->add_option("--threshold", opts->import.alpha_threshold,
                  "Alpha level of the boundary, in (0, 1): pixels above it are inside")
      ->capture_default_str();
  cmd->add_option("--tolerance", opts->import.tolerance,
                  "Simplification tolerance in pixels (Douglas-Peucker); smaller keeps more vertices")
      ->capture_default_str();
  cmd->add_option("--pixel-size", opts->import.pixel_size, "Scene units per pixel")->capture_default_str();
  cmd->add_option("--max-edge", opts->max_edge,
                  "After simplifying, split edges longer than this many pixels into equal parts; 0: off")
      ->capture_default_str();
  cmd->add_option("--min-hole-area", opts->import.min_hole_area, "Drop (fill) holes smaller than this many square pixels")
      ->capture_default_str();
  cmd->add_flag("--keep-narrow-holes", [opts](int64_t) { opts->import.fill_narrow_holes = false; },
                "Refuse the sprite, naming the hole, instead of filling a hole too narrow for a cage");
  cmd->add_option("--name", opts->name, "Scene name; default: the sprite's file name without extension");
  cmd->callback([opts] { run(*opts); });
}

}  // namespace hsi::cli
