// hsi import-glyph: one character of a font as a scene (its counters become holes).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "hsi/glyph_import.h"
#include "hsi/scene_io.h"

namespace hsi::cli {

namespace {

struct ImportGlyphOptions {
  std::string character;
  std::filesystem::path output;
  std::filesystem::path font;
  double height = 1.0;
  double flatness = 0.002;
  double max_edge = 0;
  std::filesystem::path texture;
  double texture_margin = 0.05;
  std::string name;
};

// One code point from a UTF-8 string of exactly one character, or from "U+XXXX".
char32_t parse_character(const std::string& s) {
  if (s.size() > 2 && (s[0] == 'U' || s[0] == 'u') && s[1] == '+') {
    const std::string hex = s.substr(2);
    if (hex.size() <= 6 && hex.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos) {
      const unsigned long v = std::stoul(hex, nullptr, 16);
      if (v <= 0x10FFFF && !(v >= 0xD800 && v <= 0xDFFF)) return static_cast<char32_t>(v);
    }
    throw InputError("'" + s + "' is not a valid code point; write U+ and 1 to 6 hex digits up to 10FFFF");
  }
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  if (n == 0) throw InputError("the character is empty; give one character, e.g. B, or a code point such as U+0042");
  size_t len = 0;
  char32_t c = 0;
  if (b[0] < 0x80) {
    len = 1;
    c = b[0];
  } else if ((b[0] & 0xE0) == 0xC0) {
    len = 2;
    c = b[0] & 0x1Fu;
  } else if ((b[0] & 0xF0) == 0xE0) {
    len = 3;
    c = b[0] & 0x0Fu;
  } else if ((b[0] & 0xF8) == 0xF0) {
    len = 4;
    c = b[0] & 0x07u;
  } else {
    throw InputError("the character '" + s + "' is not valid UTF-8");
  }
  if (n < len) throw InputError("the character '" + s + "' is not valid UTF-8");
  for (size_t i = 1; i < len; ++i) {
    if ((b[i] & 0xC0) != 0x80) throw InputError("the character '" + s + "' is not valid UTF-8");
    c = (c << 6) | (b[i] & 0x3Fu);
  }
  if (n != len)
    throw InputError("'" + s + "' is more than one character; give exactly one, e.g. B, or a code point such as U+0042");
  return c;
}


std::string default_name(char32_t c) {
  if ((c >= U'0' && c <= U'9') || (c >= U'A' && c <= U'Z') || (c >= U'a' && c <= U'z'))
    return std::string("glyph_") + static_cast<char>(c);
  char buf[24];
  std::snprintf(buf, sizeof buf, "glyph_U%04X", static_cast<unsigned>(c));
  return buf;
}

void run(const ImportGlyphOptions& o) {
  const char32_t c = parse_character(o.character);
  GlyphImportOptions gopt;
  gopt.font = o.font;
  gopt.height = o.height;
  gopt.flatness = o.flatness;
  Shape shape = import_glyph(c, gopt);
  if (o.max_edge > 0) {
    shape.outer = subdivide_edges(shape.outer, o.max_edge * o.height);
    for (Loop& h : shape.holes) h = subdivide_edges(h, o.max_edge * o.height);
    validate(shape);
  }

  Scene scene;
  scene.name = o.name.empty() ? default_name(c) : o.name;
  scene.shape = shape;
  const std::filesystem::path out_abs = std::filesystem::absolute(o.output).lexically_normal();
  scene.base_dir = out_abs.parent_path();
  if (!o.texture.empty()) {
    if (!std::filesystem::is_regular_file(o.texture))
      throw InputError("texture file '" + o.texture.string() + "' does not exist");
    const std::filesystem::path tex_abs = std::filesystem::absolute(o.texture).lexically_normal();
    std::filesystem::path rel = tex_abs.lexically_relative(scene.base_dir);
    scene.texture = rel.empty() ? tex_abs : rel;
    // The texture covers the bounding box expanded by the margin on every side.
    const BoundingBox bb = bounding_box(shape);
    const double mx = o.texture_margin * (bb.hi.real() - bb.lo.real());
    const double my = o.texture_margin * (bb.hi.imag() - bb.lo.imag());
    scene.texture_rect = std::array<double, 4>{bb.lo.real() - mx, bb.lo.imag() - my, bb.hi.real() + mx,
                                               bb.hi.imag() + my};
  }
  save_scene(scene, o.output);

  const BoundingBox bb = bounding_box(shape);
  std::printf("wrote %s: %s, outer loop %zu vertices", o.output.string().c_str(), describe_codepoint(c).c_str(),
              shape.outer.size());
  if (shape.holes.empty()) {
    std::printf(", no holes");
  } else {
    std::printf(", %zu hole%s (", shape.holes.size(), shape.holes.size() == 1 ? "" : "s");
    for (size_t i = 0; i < shape.holes.size(); ++i)
      std::printf("%s%zu", i ? ", " : "", shape.holes[i].size());
    std::printf(" vertices)");
  }
  std::printf(", size %.4g x %.4g\n", bb.hi.real() - bb.lo.real(), bb.hi.imag() - bb.lo.imag());
}

}  // namespace

void register_import_glyph(CLI::App& app) {
  auto opts = std::make_shared<ImportGlyphOptions>();
  CLI::App* cmd = app.add_subcommand(
      "import-glyph",
      "Import one character of a font as a scene: its outline becomes the outer loop and\n"
      "its enclosed counters (as in B, A, 8) the holes. The glyph must be one connected piece.");
  cmd->add_option("CHAR", opts->character, "The character (UTF-8), or a code point such as U+0042")->required();
  cmd->add_option("-o,--output", opts->output, "Scene file to write (JSON)")->required();
  cmd->add_option("--font", opts->font, "Font file (TrueType/OpenType); default: DejaVu Sans");
  cmd->add_option("--height", opts->height, "Height of the glyph's bounding box in scene units")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--flatness", opts->flatness,
                  "Largest deviation of the flattened curves from the outline, relative to the height")
      ->capture_default_str()
      ->check(CLI::Range(1e-7, 0.1));
  cmd->add_option("--max-edge", opts->max_edge,
                  "Split edges longer than this (relative to the height) into equal parts; 0: off")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--texture", opts->texture,
                  "Texture image; stored relative to the scene's folder, covering the glyph's\n"
                  "bounding box expanded by --texture-margin");
  cmd->add_option("--texture-margin", opts->texture_margin,
                  "Margin of the texture rectangle around the bounding box, relative to its size")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--name", opts->name, "Scene name; default: glyph_<CHAR>");
  cmd->callback([opts] { run(*opts); });
}

}  // namespace hsi::cli
