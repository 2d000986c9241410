// Font glyphs as shapes: one character's outline, flattened to polygons, with its
// counters (the enclosed holes of 'B', 'A', '8', ...) as holes.
//
// The outline is read unhinted in font units (FreeType), its conic and cubic Bézier
// segments are flattened adaptively, and contours are sorted into the outer loop and
// holes by containment (not by the font's winding convention). The result is scaled
// so that its bounding box is `height` tall with its bottom-left corner at the origin,
// then normalized and validated.
#pragma once

#include <filesystem>

#include "hsi/domain.h"

namespace hsi {

struct GlyphImportOptions {
  std::filesystem::path font;  // empty: DejaVu Sans (the font of Debian's fonts-dejavu-core)
  double height = 1.0;         // output size: the glyph's bounding-box height in output units
  double flatness = 0.002;     // max deviation of the flattened curves, relative to height
};

// The path of the default font (DejaVu Sans), as configured at build time.
std::filesystem::path default_glyph_font();

// Throws InputError, naming the font and the character, when the font is missing or
// unreadable, the character is not in the font, the glyph has no outline (a space),
// the glyph is made of several separate pieces ('i', '%', '"'), the options are out
// of range, or the flattened outline is not a valid shape.
Shape import_glyph(char32_t codepoint, const GlyphImportOptions& options = {});

// "'B' (U+0042)" for printable characters, "U+0020" otherwise: used in messages.
std::string describe_codepoint(char32_t codepoint);

}  // namespace hsi
