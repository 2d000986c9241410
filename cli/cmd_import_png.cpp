// hsi import-png: a sprite's alpha channel as a scene, textured with the sprite.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

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
  std::string crop;             // "X,Y,W,H"
  std::string filter = "auto";  // auto | linear | nearest
  bool list_pieces = false, all_pieces = false;
};

PixelRect parse_crop(const std::string& text) {
  std::istringstream in(text);
  PixelRect r;
  char c1 = 0, c2 = 0, c3 = 0, extra = 0;
  if (!(in >> r.x >> c1 >> r.y >> c2 >> r.width >> c3 >> r.height) || c1 != ',' || c2 != ',' || c3 != ',' || (in >> extra))
    throw InputError("--crop '" + text.substr(0, 60) + "': expected X,Y,W,H (whole pixels: the top-left pixel's column and row from "
                     "the top, then width and height)");
  return r;
}

// One scene from one piece of the sprite, written to `output`.
void import_one(const ImportPngOptions& o, const PngImportOptions& import, const std::filesystem::path& output,
                const std::string& name) {
  PngShape png = import_png_alpha(o.sprite, import);
  if (o.max_edge > 0) {
    const double len = o.max_edge * import.pixel_size;
    png.shape.outer = subdivide_edges(png.shape.outer, len);
    for (Loop& h : png.shape.holes) h = subdivide_edges(h, len);
    validate(png.shape);
  }

  Scene scene;
  scene.name = name;
  scene.shape = png.shape;
  const std::filesystem::path out_abs = std::filesystem::absolute(output).lexically_normal();
  scene.base_dir = out_abs.parent_path();
  const std::filesystem::path sprite_abs = std::filesystem::absolute(o.sprite).lexically_normal();
  const std::filesystem::path rel = sprite_abs.lexically_relative(scene.base_dir);
  scene.texture = rel.empty() ? sprite_abs : rel;
  scene.texture_rect = png.texture_rect;
  scene.texture_filter = png.filter;
  save_scene(scene, output);

  const Shape& s = png.shape;
  std::printf("wrote %s: %s %dx%d px", output.string().c_str(), o.sprite.string().c_str(), png.width, png.height);
  if (png.pieces > 1) std::printf(", piece %d of %d", png.piece, png.pieces);
  std::printf(", outer loop %zu vertices", s.outer.size());
  if (s.holes.empty()) {
    std::printf(", no holes");
  } else {
    std::printf(", %zu hole%s (", s.holes.size(), s.holes.size() == 1 ? "" : "s");
    for (size_t i = 0; i < s.holes.size(); ++i) std::printf("%s%zu", i ? ", " : "", s.holes[i].size());
    std::printf(" vertices)");
  }
  std::printf("; outline within %.3g px of the traced boundary (--tolerance%s)", png.tolerance,
              png.tolerance_auto ? " auto: 0.5% of the piece's longer side, 0.1 to 0.75 px" : "");
  std::printf("; texture filter %s (%s)", texture_filter_name(png.filter),
              png.filter_auto ? (png.filter == TextureFilter::Nearest ? "auto: a pixel-art size, up to 128 px" : "auto: larger than 128 px")
                              : "--filter");
  for (const std::string& w : png.warnings) std::printf("; warning: %s", w.c_str());
  std::printf("\n");
}

void run(const ImportPngOptions& o) {
  PngImportOptions import = o.import;
  if (!o.crop.empty()) import.crop = parse_crop(o.crop);
  if (o.filter != "auto") import.filter = parse_texture_filter(o.filter);
  if (o.list_pieces) {
    const std::vector<PngPiece> pieces = list_png_pieces(o.sprite, import);
    std::printf("%s: %zu piece%s (index: bounding box x,y,width,height in pixels from the top-left; area in square pixels)\n",
                o.sprite.string().c_str(), pieces.size(), pieces.size() == 1 ? "" : "s");
    for (const PngPiece& p : pieces)
      std::printf("  piece %-3d box %d,%d,%d,%d  area %.1f  %d hole%s\n", p.index, p.box.x, p.box.y, p.box.width, p.box.height, p.area,
                  p.holes, p.holes == 1 ? "" : "s");
    std::printf("import one with --piece K (or --crop X,Y,W,H), or every one with --all-pieces\n");
    if (o.output.empty()) return;
  }
  if (o.output.empty()) throw InputError("import-png: give -o SCENE.json (or --list-pieces to list the sprite's pieces)");
  std::error_code ec;
  if (std::filesystem::equivalent(o.sprite, o.output, ec))
    throw InputError("the output scene '" + o.output.string() + "' is the sprite itself; choose another file");
  if (!(o.max_edge >= 0) || !std::isfinite(o.max_edge))
    throw InputError("--max-edge must be >= 0 pixels (0: off), got " + std::to_string(o.max_edge));
  const std::string base_name = o.name.empty() ? o.sprite.stem().string() : o.name;
  if (!o.all_pieces) {
    import_one(o, import, o.output, base_name);
  } else {
    // One scene per piece: OUT_pieceK.json beside OUT.
    const size_t n = list_png_pieces(o.sprite, import).size();
    for (size_t k = 0; k < n; ++k) {
      PngImportOptions one = import;
      one.piece = static_cast<int>(k);
      std::filesystem::path out = o.output;
      out.replace_filename(o.output.stem().string() + "_piece" + std::to_string(k) + o.output.extension().string());
      try {
        import_one(o, one, out, base_name + " piece " + std::to_string(k));
      } catch (const InputError& e) {  // a speck among the pieces: say so and go on with the others
        std::printf("piece %zu not imported: %s\n", k, e.what());
      }
    }
  }
  std::printf("next: %s\n", kHowToAddKeyframes);
}

}  // namespace

void register_import_png(CLI::App& app) {
  auto opts = std::make_shared<ImportPngOptions>();
  CLI::App* cmd = app.add_subcommand(
      "import-png",
      "Import a sprite's alpha channel as a scene. The boundary is the iso-line of alpha at\n"
      "--threshold (marching squares with sub-pixel vertices), simplified to within\n"
      "--tolerance pixels. Transparent regions enclosed by the sprite become holes; if the\n"
      "sprite has several separate pieces (a sprite sheet), the largest is kept (with a warning)\n"
      "unless --piece, --crop or --all-pieces picks (--list-pieces lists them), and\n"
      "holes under --min-hole-area square pixels are dropped. The import checks that the scene\n"
      "gets a cage: holes too narrow for one (slivers) are filled, narrowest first, with a\n"
      "warning naming each. Shapes under 16 square pixels are refused. The scene is textured with the sprite: y\n"
      "points up, pixel (0,0) is the top-left corner at (0, height * pixel size), and the\n"
      "texture rectangle covers the whole image. Accepts RGBA, grey+alpha and palette\n"
      "images with transparency (tRNS), 8 or 16 bits; images without alpha are refused.");
  cmd->add_option("SPRITE", opts->sprite, "The sprite (PNG with an alpha channel)")->required();
  cmd->add_option("-o,--output", opts->output,
                  "Scene file to write (JSON); the sprite is referenced relative to its folder (with --all-pieces: "
                  "OUT_pieceK.json, one per piece)");
  cmd->add_option("--threshold", opts->import.alpha_threshold,
                  "Alpha level of the boundary, in (0, 1): pixels above it are inside")
      ->capture_default_str();
  cmd->add_option("--tolerance", opts->import.tolerance,
                  "Simplification tolerance in pixels (Douglas-Peucker); smaller keeps more vertices; 0: automatic, 0.5% "
                  "of the piece's longer side between 0.1 and 0.75 px (a 30 px sprite: 0.15 px)")
      ->capture_default_str();
  auto* piece = cmd->add_option("--piece", opts->import.piece,
                                "Import this piece (--list-pieces gives the indices) instead of the largest")
                    ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--list-pieces", opts->list_pieces,
                "List the sprite's pieces (index, bounding box in pixels, area, holes); with -o, import as well");
  cmd->add_flag("--all-pieces", opts->all_pieces, "Import every piece as its own scene, OUT_pieceK.json")->excludes(piece);
  cmd->add_option("--crop", opts->crop,
                  "Trace only the pixel rectangle X,Y,W,H (a sprite sheet's cell; column and row of its top-left pixel from "
                  "the image's top-left corner, width, height); the texture stays the whole image");
  cmd->add_option("--filter", opts->filter,
                  "The scene's texture filtering: auto (nearest for pieces up to 128 px, crisp pixel art; linear above), "
                  "linear or nearest")
      ->check(CLI::IsMember({"auto", "linear", "nearest"}))
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
