// Importing a shape from the alpha channel of a PNG sprite.
//
// The boundary is the iso-line of alpha at `alpha_threshold`, traced by marching
// squares on the pixel centres (the image is padded with one transparent pixel so
// that every contour closes), with vertices interpolated linearly along cell edges.
// Saddle cells (two opposite corners opaque, the other two transparent) are decided
// by the average of the four corners, i.e. the bilinear interpolant at the cell
// centre: above the threshold the opaque corners are joined, otherwise they are
// separated. Loops are classified as boundaries (opaque on their inside) or holes,
// each hole is given to the smallest boundary that contains it. One piece (a boundary
// with its holes) is kept: `piece` (list_png_pieces's order: by the top, then the left,
// of its bounding box), or by default the largest (boundary area minus its holes), and
// the others are dropped with a warning; `crop` traces only a rectangle of the image
// (a sprite sheet's cell). Holes under min_hole_area (4 px²) are dropped with a
// warning. A piece under
// kPngMinShapeArea is refused (too small to interpolate: a one-pixel sprite would be
// a 3-vertex triangle). Each loop is then simplified with
// Douglas–Peucker for closed polylines, at `tolerance` pixels or, by default, 0.5% of
// the kept piece's longer side between 0.1 and 0.75 px (a fixed 0.75 px made small
// sprites visibly faceted: 2.5% of a 30 px sprite); a loop whose simplification would cross
// itself or another loop is simplified again at a smaller tolerance, down to no
// simplification at all (the traced loops are simple and disjoint).
//
// The import checks its own output: the scene must get a cage (build_cage with the
// default options). A hole too narrow for its cage (a sliver, inscribed radius under
// sufficient_hole_radius(), cage.h) is filled, narrowest first and only while the cage
// cannot be built, with a warning naming it (pixel position, area, width); if the cage
// still cannot be built the import is refused, naming why and what to try.
//
// Coordinates: pixel (i, j) (column i, row j from the top) covers the output square
// [i, i+1] × [H−j−1, H−j] times pixel_size, so y points up and texture_rect, which
// covers the whole image, maps the sprite onto the shape unchanged.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hsi/domain.h"
#include "hsi/png.h"  // the decoder, kPngMaxSide, check_png_texture, check_png_payload
#include "hsi/texture_filter.h"

namespace hsi {

// A crop rectangle in pixels: column x, row y (from the top) of its top-left pixel, and its size.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

// Images up to this many pixels on their longer side get nearest texture filtering by
// default (pixel-art sizes: a 32 px sprite drawn at 1024 px stays crisp), larger ones linear.
inline constexpr int kPngPixelArtSide = 128;

struct PngImportOptions {
  double alpha_threshold = 0.5;  // in (0,1); the contour is the iso-line of alpha at this level
  double tolerance = 0;          // simplification tolerance in pixels (Douglas–Peucker on closed
                                 // loops); 0: automatic (png_tolerance_for)
  int piece = -1;                // which piece to keep (list_png_pieces's index); -1: the largest
  std::optional<PixelRect> crop; // trace only these pixels (the texture stays the whole image)
  std::optional<TextureFilter> filter;  // the scene's texture filter; default: nearest up to
                                        // kPngPixelArtSide px, else linear
  double pixel_size = 1.0;       // output units per pixel
  double min_hole_area = 4.0;    // px²: smaller holes are dropped (filled) with a warning
  bool fill_narrow_holes = true; // fill holes too narrow for a cage (else refuse, naming them)
};

// Smallest accepted shape (the kept piece, holes subtracted), in square pixels.
inline constexpr double kPngMinShapeArea = 16.0;

// The automatic simplification tolerance for a piece whose bounding box's longer side
// is `side_px`: 0.5% of it, between 0.1 and 0.75 px.
double png_tolerance_for(double side_px);

struct PngShape {
  Shape shape;                          // normalized (outer CCW, holes CW) and validated
  int width = 0, height = 0;            // image size in pixels
  double tolerance = 0;                 // the simplification tolerance used, in pixels
  bool tolerance_auto = false;          // chosen by png_tolerance_for
  int piece = 0, pieces = 1;            // the kept piece's index, of this many
  TextureFilter filter = TextureFilter::Linear;
  bool filter_auto = false;             // chosen by image size (kPngPixelArtSide)
  std::array<double, 4> texture_rect{};  // [x0,y0,x1,y1]: the whole image in output units
  std::vector<std::string> warnings;    // e.g. "dropped 2 smaller pieces (largest kept: 93% of the opaque area)"
};

// Reads RGBA, grey+alpha, or any PNG with a tRNS chunk (palette, grey or RGB),
// 8 or 16 bits. Throws InputError naming the file and the problem: missing file,
// not a PNG, corrupt or truncated data, no alpha channel, no opaque pixels, image
// too large, bad options, or a shape that fails validate().
PngShape import_png_alpha(const std::filesystem::path& png, const PngImportOptions& options = {});
// The same from the file's bytes in memory; `name` is used in messages.
PngShape import_png_alpha(std::span<const unsigned char> png_bytes, const std::string& name,
                          const PngImportOptions& options = {});

// The pieces of an image (after alpha_threshold and crop), in the order `piece` indexes
// them: by the top, then the left, of their bounding boxes.
struct PngPiece {
  int index = 0;
  PixelRect box;      // the pixels it covers (column, row from the top, size)
  double area = 0;    // traced area in square pixels, holes subtracted
  int holes = 0;
};
std::vector<PngPiece> list_png_pieces(const std::filesystem::path& png, const PngImportOptions& options = {});
std::vector<PngPiece> list_png_pieces(std::span<const unsigned char> png_bytes, const std::string& name,
                                      const PngImportOptions& options = {});

}  // namespace hsi
