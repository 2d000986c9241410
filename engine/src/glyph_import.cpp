// Font glyph outlines as shapes (FreeType; see glyph_import.h).
#include "hsi/glyph_import.h"

#include <ft2build.h>
#include FT_FREETYPE_H
#include FT_OUTLINE_H
#include FT_BBOX_H

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#ifndef HSI_DEJAVU_FONT
#define HSI_DEJAVU_FONT "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#endif

namespace hsi {

std::filesystem::path default_glyph_font() { return HSI_DEJAVU_FONT; }

namespace {

void append_utf8(std::string& s, char32_t c) {
  if (c < 0x80) {
    s += static_cast<char>(c);
  } else if (c < 0x800) {
    s += static_cast<char>(0xC0 | (c >> 6));
    s += static_cast<char>(0x80 | (c & 0x3F));
  } else if (c < 0x10000) {
    s += static_cast<char>(0xE0 | (c >> 12));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    s += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    s += static_cast<char>(0xF0 | (c >> 18));
    s += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    s += static_cast<char>(0x80 | (c & 0x3F));
  }
}

bool printable(char32_t c) {
  if (c > 0x20 && c < 0x7F) return true;  // visible ASCII
  if (c < 0xA1 || c > 0x10FFFF) return false;
  if (c >= 0xD800 && c <= 0xDFFF) return false;   // surrogates
  if (c >= 0xE000 && c <= 0xF8FF) return false;   // private use
  if (c >= 0xF0000) return false;                 // supplementary private use
  if ((c & 0xFFFE) == 0xFFFE) return false;       // noncharacters
  return true;
}

struct LibraryDeleter {
  void operator()(FT_Library lib) const { FT_Done_FreeType(lib); }
};
struct FaceDeleter {
  void operator()(FT_Face face) const { FT_Done_Face(face); }
};
using LibraryPtr = std::unique_ptr<std::remove_pointer_t<FT_Library>, LibraryDeleter>;
using FacePtr = std::unique_ptr<std::remove_pointer_t<FT_Face>, FaceDeleter>;

// Collects the flattened contours of an outline, in font units.
struct Flattener {
  double tolerance;  // max deviation, font units
  std::vector<Loop> contours;
  cd current{0, 0};

  static cd point(const FT_Vector* v) { return {static_cast<double>(v->x), static_cast<double>(v->y)}; }

  // Pieces needed so that each piece of a Bézier whose deviation bound is `bound`
  // deviates from its chord by at most tolerance: splitting into n equal parameter
  // pieces divides the second differences, hence the bound, by n².
  int pieces(double bound) const {
    if (!(bound > tolerance)) return 1;
    const double n = std::ceil(std::sqrt(bound / tolerance));
    return static_cast<int>(std::min(n, 4096.0));
  }

  void line_to(cd p) {
    if (contours.empty()) contours.emplace_back();
    contours.back().push_back(p);
    current = p;
  }

  // Quadratic Bézier: B(t) − chord(t) = −t(1−t)(P0 − 2P1 + P2), at most |P0 − 2P1 + P2| / 4.
  void conic_to(cd c, cd p) {
    const cd p0 = current;
    const int n = pieces(std::abs(p0 - 2.0 * c + p) / 4.0);
    for (int i = 1; i <= n; ++i) {
      const double t = static_cast<double>(i) / n, s = 1.0 - t;
      line_to(s * s * p0 + 2.0 * s * t * c + t * t * p);
    }
    current = p;
  }

  // Cubic Bézier: the deviation from the chord is at most 3/4 of the largest second difference.
  void cubic_to(cd c1, cd c2, cd p) {
    const cd p0 = current;
    const double d = std::max(std::abs(p0 - 2.0 * c1 + c2), std::abs(c1 - 2.0 * c2 + p));
    const int n = pieces(0.75 * d);
    for (int i = 1; i <= n; ++i) {
      const double t = static_cast<double>(i) / n, s = 1.0 - t;
      line_to(s * s * s * p0 + 3.0 * s * s * t * c1 + 3.0 * s * t * t * c2 + t * t * t * p);
    }
    current = p;
  }

  static int on_move(const FT_Vector* to, void* user) {
    auto* self = static_cast<Flattener*>(user);
    self->contours.emplace_back();
    self->contours.back().push_back(point(to));
    self->current = point(to);
    return 0;
  }
  static int on_line(const FT_Vector* to, void* user) {
    static_cast<Flattener*>(user)->line_to(point(to));
    return 0;
  }
  static int on_conic(const FT_Vector* control, const FT_Vector* to, void* user) {
    static_cast<Flattener*>(user)->conic_to(point(control), point(to));
    return 0;
  }
  static int on_cubic(const FT_Vector* c1, const FT_Vector* c2, const FT_Vector* to, void* user) {
    static_cast<Flattener*>(user)->cubic_to(point(c1), point(c2), point(to));
    return 0;
  }
};

// Drops the repeated closing point and every zero-length edge (exact repeats, and
// points closer than `eps` to their predecessor).
Loop clean_contour(const Loop& in, double eps) {
  Loop out;
  out.reserve(in.size());
  for (const cd& p : in)
    if (out.empty() || std::abs(p - out.back()) > eps) out.push_back(p);
  while (out.size() > 1 && std::abs(out.back() - out.front()) <= eps) out.pop_back();
  return out;
}

// Whether contour a lies inside contour b. Contours of a valid glyph do not cross,
// so one vertex decides; a majority over several vertices guards against vertices
// that sit exactly on the other contour (touching contours).
bool contour_inside(const Loop& a, const Loop& b) {
  const size_t samples = std::min<size_t>(a.size(), 7);
  int votes = 0;
  for (size_t k = 0; k < samples; ++k) votes += point_in_loop(b, a[k * a.size() / samples]) ? 1 : -1;
  return votes > 0;
}

}  // namespace

std::string describe_codepoint(char32_t codepoint) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "U+%04X", static_cast<unsigned>(codepoint));
  if (!printable(codepoint)) return hex;
  std::string s = "'";
  append_utf8(s, codepoint);
  return s + "' (" + hex + ")";
}

Shape import_glyph(char32_t codepoint, const GlyphImportOptions& options) {
  const std::filesystem::path font = options.font.empty() ? default_glyph_font() : options.font;
  const std::string what = "character " + describe_codepoint(codepoint);
  std::string font_name = "font '" + font.string() + "'";

  if (!std::isfinite(options.height) || options.height <= 0)
    throw InputError("glyph import of " + what + ": height must be a positive number, got " +
                     std::to_string(options.height));
  if (!std::isfinite(options.flatness) || options.flatness < 1e-7 || options.flatness > 0.1)
    throw InputError("glyph import of " + what + ": flatness must lie in [1e-7, 0.1] (relative to the height), got " +
                     std::to_string(options.flatness));

  std::error_code ec;
  if (!std::filesystem::exists(font, ec))
    throw InputError(font_name + " does not exist (needed for " + what + ")");
  if (std::filesystem::is_directory(font, ec))
    throw InputError(font_name + " is a directory, not a font file (needed for " + what + ")");

  FT_Library raw_lib = nullptr;
  if (FT_Error err = FT_Init_FreeType(&raw_lib))
    throw std::runtime_error("FreeType failed to initialise (error " + std::to_string(err) + ")");
  LibraryPtr lib(raw_lib);

  FT_Face raw_face = nullptr;
  if (FT_Error err = FT_New_Face(lib.get(), font.c_str(), 0, &raw_face))
    throw InputError("cannot read " + font_name + " as a font (FreeType error " + std::to_string(err) +
                     "; needed for " + what + ")");
  FacePtr face(raw_face);
  if (face->family_name) {
    std::string family = face->family_name;
    if (face->style_name && std::string(face->style_name) != "Regular") family += std::string(" ") + face->style_name;
    font_name = "font " + family + " ('" + font.string() + "')";
  }
  if (!FT_IS_SCALABLE(face))
    throw InputError(font_name + " has no outlines (a bitmap font); needed for " + what);

  // FreeType selects a Unicode charmap by default when the font has one.
  const FT_UInt index = FT_Get_Char_Index(face.get(), static_cast<FT_ULong>(codepoint));
  if (index == 0) throw InputError(font_name + " has no glyph for " + what);
  if (FT_Error err = FT_Load_Glyph(face.get(), index, FT_LOAD_NO_SCALE | FT_LOAD_NO_HINTING | FT_LOAD_NO_BITMAP))
    throw InputError(font_name + " failed to load the glyph for " + what + " (FreeType error " + std::to_string(err) +
                     ")");
  FT_GlyphSlot slot = face->glyph;
  if (slot->format != FT_GLYPH_FORMAT_OUTLINE)
    throw InputError("the glyph for " + what + " in " + font_name + " is not an outline");
  FT_Outline& outline = slot->outline;
  if (outline.n_contours <= 0 || outline.n_points <= 0)
    throw InputError("the glyph for " + what + " in " + font_name +
                     " has no outline (a blank character such as a space); hsi needs a filled shape");

  // The exact bounding box (in font units) sets the flattening tolerance.
  FT_BBox bbox;
  FT_Outline_Get_BBox(&outline, &bbox);
  const double units_height = static_cast<double>(bbox.yMax - bbox.yMin);
  if (!(units_height > 0))
    throw InputError("the glyph for " + what + " in " + font_name + " has zero height; hsi needs a filled shape");

  Flattener flat{options.flatness * units_height, {}, {0, 0}};
  FT_Outline_Funcs funcs{};
  funcs.move_to = &Flattener::on_move;
  funcs.line_to = &Flattener::on_line;
  funcs.conic_to = &Flattener::on_conic;
  funcs.cubic_to = &Flattener::on_cubic;
  funcs.shift = 0;
  funcs.delta = 0;
  if (FT_Error err = FT_Outline_Decompose(&outline, &funcs, &flat))
    throw InputError("cannot decompose the outline of " + what + " in " + font_name + " (FreeType error " +
                     std::to_string(err) + ")");

  // Clean the contours; drop degenerate ones (fewer than 3 vertices or no area).
  const double eps = 1e-9 * units_height;
  std::vector<Loop> contours;
  for (const Loop& c : flat.contours) {
    Loop loop = clean_contour(c, eps);
    if (loop.size() >= 3 && std::abs(signed_area(loop)) > 1e-12 * units_height * units_height)
      contours.push_back(std::move(loop));
  }
  if (contours.empty())
    throw InputError("the glyph for " + what + " in " + font_name +
                     " has no outline (a blank character such as a space); hsi needs a filled shape");

  // Scale: the flattened polygon's bounding box becomes [0, w] × [0, height].
  double xmin = INFINITY, ymin = INFINITY, ymax = -INFINITY;
  for (const Loop& c : contours)
    for (const cd& p : c) {
      xmin = std::min(xmin, p.real());
      ymin = std::min(ymin, p.imag());
      ymax = std::max(ymax, p.imag());
    }
  const double scale = options.height / (ymax - ymin);
  for (Loop& c : contours)
    for (cd& p : c) p = (p - cd{xmin, ymin}) * scale;

  // Containment depth of each contour: even depth = a filled piece, odd = a hole.
  const size_t n = contours.size();
  std::vector<int> depth(n, 0);
  for (size_t a = 0; a < n; ++a)
    for (size_t b = 0; b < n; ++b)
      if (a != b && contour_inside(contours[a], contours[b])) ++depth[a];
  std::vector<size_t> pieces, holes;
  for (size_t a = 0; a < n; ++a) (depth[a] % 2 == 0 ? pieces : holes).push_back(a);
  if (pieces.size() != 1)
    throw InputError("the glyph for " + what + " in " + font_name + " consists of " + std::to_string(pieces.size()) +
                     " separate pieces; hsi needs one connected shape (one outer outline, with any number of holes)");

  Shape shape;
  shape.outer = std::move(contours[pieces[0]]);
  for (size_t h : holes) shape.holes.push_back(std::move(contours[h]));
  shape = normalize(std::move(shape));
  try {
    validate(shape);
  } catch (const InputError& e) {
    throw InputError("the outline of " + what + " in " + font_name + " is not a valid shape: " + e.what());
  }
  return shape;
}

}  // namespace hsi
