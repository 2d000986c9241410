// Shape from a PNG sprite's alpha channel: decode (png.h's decode_png_alpha),
// marching squares, nesting, largest piece, Douglas–Peucker (see png_import.h).
#include "hsi/png_import.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "cgal_geometry.h"
#include "hsi/cage.h"

namespace hsi {

namespace {

constexpr double kEdgeClamp = 1e-3;        // keeps contour vertices off the pixel centres
constexpr double kMinTolerance = 1e-3;     // below this a loop is left unsimplified
constexpr int kMaxSimplifyRounds = 64;

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string plural(size_t n, const std::string& word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

// ---------------------------------------------------------------------------
// Marching squares

// The image padded by one transparent pixel on every side; node (x, y) of the
// padded grid is the centre of pixel (x − 1, y − 1), at (x − 0.5, y − 0.5) in pixel
// coordinates (x right, y down).
class PaddedGrid {
 public:
  PaddedGrid(const PngAlpha& img, double threshold)
      : img_(img), nx_(img.width + 2), ny_(img.height + 2), level_(threshold * img.max_value) {}
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double value(int x, int y) const {
    if (x <= 0 || y <= 0 || x > img_.width || y > img_.height) return 0.0;
    return img_.alpha[static_cast<size_t>(y - 1) * static_cast<size_t>(img_.width) + static_cast<size_t>(x - 1)];
  }
  double level() const { return level_; }
  bool inside(double v) const { return v > level_; }
  bool inside(int x, int y) const { return inside(value(x, y)); }
  uint64_t node(int x, int y) const {
    return static_cast<uint64_t>(y) * static_cast<uint64_t>(nx_) + static_cast<uint64_t>(x);
  }
  // Edge ids: 2·node for the edge to the right neighbour, 2·node + 1 for the edge below.
  uint64_t h_edge(int x, int y) const { return 2 * node(x, y); }
  uint64_t v_edge(int x, int y) const { return 2 * node(x, y) + 1; }
  // Where the contour crosses an edge (exactly one endpoint inside), in pixel coordinates.
  cd crossing(uint64_t edge) const {
    const uint64_t nd = edge / 2;
    const int x = static_cast<int>(nd % static_cast<uint64_t>(nx_));
    const int y = static_cast<int>(nd / static_cast<uint64_t>(nx_));
    const int x1 = (edge & 1) ? x : x + 1;
    const int y1 = (edge & 1) ? y + 1 : y;
    const double a0 = value(x, y), a1 = value(x1, y1);
    const double s = std::clamp((level_ - a0) / (a1 - a0), kEdgeClamp, 1.0 - kEdgeClamp);
    const cd p0(x - 0.5, y - 0.5), p1(x1 - 0.5, y1 - 0.5);
    return p0 + s * (p1 - p0);
  }

 private:
  const PngAlpha& img_;
  int nx_, ny_;
  double level_;
};

// All iso-lines, as closed loops in pixel coordinates, each with the opaque side on
// its left when x is right and y is down taken as a right-handed frame: boundaries
// then have positive signed area and holes negative.
std::vector<Loop> trace_contours(const PaddedGrid& g) {
  std::unordered_map<uint64_t, uint64_t> next;  // directed contour segments, edge to edge
  for (int cy = 0; cy + 1 < g.ny(); ++cy) {
    for (int cx = 0; cx + 1 < g.nx(); ++cx) {
      // Corners in cyclic order c0 (x,y), c1 (x+1,y), c2 (x+1,y+1), c3 (x,y+1);
      // edge k joins corner k to corner k+1.
      const double v[4] = {g.value(cx, cy), g.value(cx + 1, cy), g.value(cx + 1, cy + 1), g.value(cx, cy + 1)};
      const bool in[4] = {g.inside(v[0]), g.inside(v[1]), g.inside(v[2]), g.inside(v[3])};
      if (in[0] == in[1] && in[1] == in[2] && in[2] == in[3]) continue;
      const uint64_t edge[4] = {g.h_edge(cx, cy), g.v_edge(cx + 1, cy), g.h_edge(cx, cy + 1), g.v_edge(cx, cy)};
      int crossings[4], count = 0;
      for (int k = 0; k < 4; ++k)
        if (in[k] != in[(k + 1) % 4]) crossings[count++] = k;
      // A segment runs from each edge left opaque→transparent to an edge entered
      // transparent→opaque, keeping the opaque corner(s) on its left. With two
      // crossings there is one choice. In a saddle (four crossings) the next crossing
      // cuts off a transparent corner (opaque corners joined), the previous one cuts
      // off the opaque corner (opaque corners apart); the bilinear interpolant at the
      // cell centre, the mean of the corners, decides.
      const bool joined = g.inside(0.25 * (v[0] + v[1] + v[2] + v[3]));
      for (int i = 0; i < count; ++i) {
        const int k = crossings[i];
        if (!in[k]) continue;  // transparent→opaque: a segment ends here
        const int j = joined ? (i + 1) % count : (i + count - 1) % count;
        next.emplace(edge[k], edge[crossings[j]]);
      }
    }
  }
  std::vector<Loop> loops;
  while (!next.empty()) {
    const uint64_t start = next.begin()->first;
    Loop loop;
    uint64_t cur = start;
    do {
      loop.push_back(g.crossing(cur));
      const auto it = next.find(cur);
      if (it == next.end()) throw std::logic_error("png import: open contour");  // cannot happen
      cur = it->second;
      next.erase(it);
    } while (cur != start);
    // Start at the top-most, then left-most vertex, so results do not depend on
    // the hash map's iteration order.
    const auto first = std::min_element(loop.begin(), loop.end(), [](const cd& p, const cd& q) {
      return std::make_pair(p.imag(), p.real()) < std::make_pair(q.imag(), q.real());
    });
    std::rotate(loop.begin(), first, loop.end());
    loops.push_back(std::move(loop));
  }
  return loops;
}

// ---------------------------------------------------------------------------
// Douglas–Peucker on a closed polyline

Loop simplify_closed(const Loop& loop, double tol) {
  const size_t n = loop.size();
  if (n <= 3 || tol <= 0) return loop;
  // Anchors independent of tol (so a larger tol keeps a subset of the vertices): the
  // lowest-leftmost vertex and the vertex farthest from it.
  size_t a = 0;
  for (size_t i = 1; i < n; ++i)
    if (loop[i].real() < loop[a].real() || (loop[i].real() == loop[a].real() && loop[i].imag() < loop[a].imag()))
      a = i;
  size_t b = a;
  for (size_t i = 0; i < n; ++i)
    if (std::abs(loop[i] - loop[a]) > std::abs(loop[b] - loop[a])) b = i;
  auto at = [&](size_t k) -> const cd& { return loop[(a + k) % n]; };  // offsets from a
  const size_t mb = (b + n - a) % n;
  std::vector<char> keep(n, 0);
  keep[0] = keep[mb] = 1;
  std::vector<std::pair<size_t, size_t>> stack{{0, mb}, {mb, n}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    size_t best = i;
    double dmax = -1;
    for (size_t k = i + 1; k < j; ++k) {
      const double d = segment_distance(at(k), at(i), at(j));
      if (d > dmax) dmax = d, best = k;
    }
    if (dmax > tol) {
      keep[best] = 1;
      stack.emplace_back(i, best);
      stack.emplace_back(best, j);
    }
  }
  if (std::count(keep.begin(), keep.end(), 1) < 3) {
    // Two anchors make no polygon: add the vertex farthest from their segment (the
    // split point of whichever chain a smaller tol would have split first).
    size_t best = 1;
    double dmax = -1;
    for (size_t k = 1; k < n; ++k) {
      if (k == mb) continue;
      const double d = segment_distance(at(k), at(0), at(mb));
      if (d > dmax) dmax = d, best = k;
    }
    keep[best] = 1;
  }
  Loop out;
  for (size_t i = 0; i < n; ++i)
    if (keep[(i + n - a) % n]) out.push_back(loop[i]);
  return out;
}

// Loops involved in a crossing, or in a containment that simplification broke
// (a hole leaving the outer loop or entering another hole). Loop 0 is the outer.
std::vector<int> conflicting_loops(const std::vector<Loop>& loops) {
  std::vector<const Loop*> ptrs;
  for (const Loop& l : loops) ptrs.push_back(&l);
  std::vector<char> bad(loops.size(), 0);
  for (const auto& [e, f] : detail::intersecting_edges(ptrs, 1u << 16)) {
    bad[static_cast<size_t>(e.loop)] = 1;
    bad[static_cast<size_t>(f.loop)] = 1;
  }
  if (std::find(bad.begin(), bad.end(), 1) == bad.end()) {
    for (size_t h = 1; h < loops.size(); ++h) {
      const cd p = loops[h][0];
      if (!point_in_loop(loops[0], p)) bad[0] = bad[h] = 1;
      for (size_t k = 1; k < loops.size(); ++k)
        if (k != h && point_in_loop(loops[k], p)) bad[k] = bad[h] = 1;
    }
  }
  std::vector<int> out;
  for (size_t i = 0; i < bad.size(); ++i)
    if (bad[i]) out.push_back(static_cast<int>(i));
  return out;
}

struct BoxD {
  double x0, y0, x1, y1;
  bool contains(const BoxD& o) const { return x0 <= o.x0 && y0 <= o.y0 && o.x1 <= x1 && o.y1 <= y1; }
};

BoxD box_of(const Loop& l) {
  const BoundingBox b = bounding_box(l);
  return {b.lo.real(), b.lo.imag(), b.hi.real(), b.hi.imag()};
}

}  // namespace

namespace {
void check_options(const PngImportOptions& options, const std::string& name) {
  const double t = options.alpha_threshold;
  if (!(t > 0 && t < 1))
    throw InputError(name + ": bad option: the alpha threshold must be in (0, 1), got " + fmt(t));
  if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance))
    throw InputError(name + ": bad option: the simplification tolerance must be > 0 pixels (0: automatic), got " +
                     fmt(options.tolerance));
  if (options.piece < -1)
    throw InputError(name + ": bad option: the piece index must be >= 0 (-1: the largest), got " + std::to_string(options.piece));
  if (!(options.pixel_size > 0) || !std::isfinite(options.pixel_size))
    throw InputError(name + ": bad option: the pixel size must be > 0, got " + fmt(options.pixel_size));
  if (!(options.min_hole_area >= 0) || !std::isfinite(options.min_hole_area))
    throw InputError(name + ": bad option: the minimum hole area must be >= 0 square pixels, got " + fmt(options.min_hole_area));
}
// The import checks its own output (png_import.h): the shape must get a cage. While
// build_cage fails, the narrowest hole under sufficient_hole_radius() is filled (or,
// without fill_narrow_holes, the import is refused naming it); a failure left over is
// refused with the cage's reason.
void fit_cage(Shape& shape, const std::string& name, const PngImportOptions& options, double height_px,
              std::vector<std::string>& warnings) {
  const double ps = options.pixel_size;
  const auto px = [&](cd p) {  // output units (y up) back to pixels (y down from the top), for messages
    char buf[64];
    std::snprintf(buf, sizeof buf, "(%.1f, %.1f) px", p.real() / ps, height_px - p.imag() / ps);
    return std::string(buf);
  };
  const double r_ok = sufficient_hole_radius(bounding_box(shape).diagonal());
  for (;;) {
    std::string why;
    try {
      (void)build_cage(shape);
      return;
    } catch (const InputError& e) {
      why = e.what();
    }
    int narrowest = -1;
    Circle c_min;
    for (size_t h = 0; h < shape.holes.size(); ++h) {
      const Circle c = largest_inscribed_circle(shape.holes[h]);
      if (c.radius < r_ok && (narrowest < 0 || c.radius < c_min.radius)) narrowest = static_cast<int>(h), c_min = c;
    }
    if (narrowest < 0)
      throw InputError(name + ": the imported shape cannot be given a cage: " + why +
                       "; try a larger --tolerance, --min-hole-area, or a larger sprite");
    const Loop& hole = shape.holes[static_cast<size_t>(narrowest)];
    char what[256];
    std::snprintf(what, sizeof what, "hole at %s (%.3g square pixels, %.2g px across at its widest; a cage needs %.2g px in a sprite this size)",
                  px(c_min.center).c_str(), std::abs(signed_area(hole)) / (ps * ps), 2 * c_min.radius / ps, 2 * r_ok / ps);
    if (!options.fill_narrow_holes)
      throw InputError(name + ": the " + what + " is too narrow for a cage (" + why +
                       "); fill it (the default, without --keep-narrow-holes), raise --min-hole-area, or widen it in the sprite");
    warnings.push_back(std::string("filled the ") + what + ", too narrow for a cage");
    shape.holes.erase(shape.holes.begin() + narrowest);
  }
}

}  // namespace

double png_tolerance_for(double side_px) { return std::clamp(0.005 * side_px, 0.1, 0.75); }

namespace {

// The image with every pixel outside options.crop made transparent (the texture
// rectangle still covers the whole image, so the sprite maps onto the piece unchanged).
PngAlpha cropped(PngAlpha img, const PngImportOptions& options, const std::string& name) {
  if (!options.crop) return img;
  const PixelRect& c = *options.crop;
  if (c.width <= 0 || c.height <= 0 || c.x < 0 || c.y < 0 || c.x + c.width > img.width || c.y + c.height > img.height)
    throw InputError(name + ": the crop rectangle " + std::to_string(c.x) + "," + std::to_string(c.y) + "," + std::to_string(c.width) +
                     "," + std::to_string(c.height) + " (x, y, width, height in pixels) does not lie inside the " +
                     std::to_string(img.width) + "x" + std::to_string(img.height) + " px image");
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (x < c.x || y < c.y || x >= c.x + c.width || y >= c.y + c.height)
        img.alpha[static_cast<size_t>(y) * static_cast<size_t>(img.width) + static_cast<size_t>(x)] = 0;
  return img;
}

// Traced loops (pixel coordinates, y down) grouped into pieces, in list_png_pieces's order.
struct Traced {
  std::vector<Loop> loops;
  std::vector<double> areas;  // signed: > 0 boundaries, < 0 holes
  struct Piece {
    size_t boundary = 0;
    std::vector<size_t> holes;
    double area = 0;  // holes subtracted
    BoxD box{};
  };
  std::vector<Piece> pieces;
};

Traced trace_pieces(const PngAlpha& img, const PngImportOptions& options, const std::string& name) {
  const double t = options.alpha_threshold;
  const PaddedGrid grid(img, t);
  if (std::none_of(img.alpha.begin(), img.alpha.end(), [&](uint16_t a) { return grid.inside(a); }))
    throw InputError(name + ": no opaque pixels above alpha threshold " + fmt(t) + " (" + std::to_string(img.width) + "x" +
                     std::to_string(img.height) + " px image" + (options.crop ? ", in the crop rectangle" : "") + ")");
  // Trace, then sort loops into boundaries and holes by orientation (the tracing
  // keeps the opaque side on the left, so this is the parity of containment depth).
  Traced tr;
  tr.loops = trace_contours(grid);
  std::vector<size_t> bounds, holes;
  tr.areas.resize(tr.loops.size());
  std::vector<BoxD> boxes(tr.loops.size());
  for (size_t i = 0; i < tr.loops.size(); ++i) {
    tr.areas[i] = signed_area(tr.loops[i]);
    boxes[i] = box_of(tr.loops[i]);
    (tr.areas[i] > 0 ? bounds : holes).push_back(i);
  }
  // Nesting: each hole belongs to the smallest boundary containing it (loops are
  // disjoint, so one vertex decides containment).
  std::sort(bounds.begin(), bounds.end(), [&](size_t x, size_t y) { return tr.areas[x] < tr.areas[y]; });
  std::unordered_map<size_t, std::vector<size_t>> holes_of;
  for (size_t h : holes) {
    const double ha = -tr.areas[h];
    for (size_t bi : bounds) {
      if (tr.areas[bi] <= ha || !boxes[bi].contains(boxes[h])) continue;
      if (point_in_loop(tr.loops[bi], tr.loops[h][0])) {
        holes_of[bi].push_back(h);
        break;
      }
    }
  }
  for (size_t bi : bounds) {
    Traced::Piece p;
    p.boundary = bi;
    p.holes = holes_of[bi];
    p.area = tr.areas[bi];
    for (size_t h : p.holes) p.area += tr.areas[h];
    p.box = boxes[bi];
    tr.pieces.push_back(std::move(p));
  }
  // Reading order: by the top, then the left, of the bounding box (ties: the larger first).
  std::sort(tr.pieces.begin(), tr.pieces.end(), [](const Traced::Piece& a, const Traced::Piece& b) {
    return std::make_tuple(a.box.y0, a.box.x0, -a.area) < std::make_tuple(b.box.y0, b.box.x0, -b.area);
  });
  return tr;
}

// The pixels a traced box covers (vertices lie between pixel centres, x right, y down).
PixelRect pixel_box(const BoxD& b) {
  const int x0 = static_cast<int>(std::floor(b.x0)), y0 = static_cast<int>(std::floor(b.y0));
  return {x0, y0, static_cast<int>(std::ceil(b.x1)) - x0, static_cast<int>(std::ceil(b.y1)) - y0};
}

}  // namespace

std::vector<PngPiece> list_png_pieces(const std::filesystem::path& png, const PngImportOptions& options) {
  const std::string name = png.string();
  check_options(options, name);
  return list_png_pieces(read_png_bytes(png, name), name, options);
}

std::vector<PngPiece> list_png_pieces(std::span<const unsigned char> png_bytes, const std::string& name,
                                      const PngImportOptions& options) {
  check_options(options, name);
  const PngAlpha img = cropped(decode_png_alpha(png_bytes, name), options, name);
  const Traced tr = trace_pieces(img, options, name);
  std::vector<PngPiece> out;
  for (size_t i = 0; i < tr.pieces.size(); ++i)
    out.push_back({static_cast<int>(i), pixel_box(tr.pieces[i].box), tr.pieces[i].area, static_cast<int>(tr.pieces[i].holes.size())});
  return out;
}

PngShape import_png_alpha(const std::filesystem::path& png, const PngImportOptions& options) {
  const std::string name = png.string();
  check_options(options, name);
  return import_png_alpha(read_png_bytes(png, name), name, options);
}

PngShape import_png_alpha(std::span<const unsigned char> png_bytes, const std::string& name, const PngImportOptions& options) {
  check_options(options, name);
  const double t = options.alpha_threshold;
  const PngAlpha img = cropped(decode_png_alpha(png_bytes, name), options, name);
  PngShape result;
  result.width = img.width;
  result.height = img.height;
  result.texture_rect = {0.0, 0.0, img.width * options.pixel_size, img.height * options.pixel_size};
  result.warnings = img.warnings;

  const Traced tr = trace_pieces(img, options, name);
  const std::vector<Loop>& loops = tr.loops;
  const std::vector<double>& areas = tr.areas;
  const size_t n_pieces = tr.pieces.size();
  size_t chosen = 0;
  double total_area = 0;
  for (size_t i = 0; i < n_pieces; ++i) {
    total_area += tr.pieces[i].area;
    if (tr.pieces[i].area > tr.pieces[chosen].area) chosen = i;
  }
  if (options.piece >= 0) {
    if (static_cast<size_t>(options.piece) >= n_pieces)
      throw InputError(name + ": piece " + std::to_string(options.piece) + " does not exist: the image has " + plural(n_pieces, "piece") +
                       " (0 to " + std::to_string(n_pieces - 1) + "; hsi import-png --list-pieces lists them)");
    chosen = static_cast<size_t>(options.piece);
  } else if (n_pieces > 1) {
    const double pct = 100.0 * tr.pieces[chosen].area / total_area;
    char buf[32];
    std::snprintf(buf, sizeof buf, pct >= 99.5 ? "%.2f%%" : pct >= 10 ? "%.0f%%" : "%.2g%%", pct);
    result.warnings.push_back("dropped " + plural(n_pieces - 1, "smaller piece") + " (largest kept: piece " + std::to_string(chosen) +
                              ", " + buf + " of the opaque area; --list-pieces lists them, --piece K, --crop or --all-pieces picks)");
  }
  const Traced::Piece& piece = tr.pieces[chosen];
  result.piece = static_cast<int>(chosen);
  result.pieces = static_cast<int>(n_pieces);
  const size_t best = piece.boundary;
  const double best_area = piece.area;
  const PixelRect pbox = pixel_box(piece.box);
  const double side = std::max(pbox.width, pbox.height);
  result.tolerance_auto = !(options.tolerance > 0);
  result.tolerance = result.tolerance_auto ? png_tolerance_for(side) : options.tolerance;
  result.filter_auto = !options.filter;
  result.filter = options.filter ? *options.filter : side <= kPngPixelArtSide ? TextureFilter::Nearest : TextureFilter::Linear;
  if (best_area < kPngMinShapeArea) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", best_area);
    throw InputError(name + ": the sprite's shape is only " + buf + " square pixels (" + std::to_string(img.width) + "x" +
                     std::to_string(img.height) + " px image, alpha threshold " + fmt(t) + "); hsi needs at least " +
                     fmt(kPngMinShapeArea) + " square pixels (e.g. 4 x 4 px) to make a shape worth interpolating");
  }
  std::vector<Loop> kept{loops[best]};
  size_t tiny = 0;
  double tiny_max = 0;
  for (size_t h : piece.holes) {
    if (-areas[h] < options.min_hole_area) {
      ++tiny;
      tiny_max = std::max(tiny_max, -areas[h]);
    } else {
      kept.push_back(loops[h]);
    }
  }
  if (tiny > 0) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2g", tiny_max);
    result.warnings.push_back("dropped " + plural(tiny, "hole") + " smaller than " + fmt(options.min_hole_area) +
                              " square pixels (largest dropped: " + buf + " square pixels)");
  }
  // Hole order: by position (top to bottom, then left to right), so that it does
  // not depend on hash-map iteration.
  std::sort(kept.begin() + 1, kept.end(), [](const Loop& x, const Loop& y) {
    const BoxD bx = box_of(x), by = box_of(y);
    return std::make_pair(bx.y0, bx.x0) < std::make_pair(by.y0, by.x0);
  });

  // Simplify; where a loop would cross itself or another, retry it at a smaller tolerance.
  std::vector<double> tol(kept.size(), result.tolerance);
  std::vector<Loop> simple(kept.size());
  for (size_t i = 0; i < kept.size(); ++i) simple[i] = simplify_closed(kept[i], tol[i]);
  size_t reduced = 0;
  std::vector<char> was_reduced(kept.size(), 0);
  for (int round = 0;; ++round) {
    const std::vector<int> bad = conflicting_loops(simple);
    if (bad.empty()) break;
    for (int bi : bad) {
      const size_t i = static_cast<size_t>(bi);
      if (!was_reduced[i]) was_reduced[i] = 1, ++reduced;
      tol[i] = round + 1 >= kMaxSimplifyRounds ? 0.0 : tol[i] / 2;
      if (tol[i] < kMinTolerance) tol[i] = 0.0;
      simple[i] = tol[i] > 0 ? simplify_closed(kept[i], tol[i]) : kept[i];
    }
    if (round > kMaxSimplifyRounds) break;  // all unsimplified by now; validate() reports anything left
  }
  if (reduced > 0)
    result.warnings.push_back("simplified " + plural(reduced, "loop") +
                              " at a smaller tolerance to keep the loops simple and apart");

  // Pixel coordinates (y down) to output units (y up).
  const double ps = options.pixel_size;
  const double hgt = img.height;
  auto to_output = [&](const Loop& l) {
    Loop o;
    o.reserve(l.size());
    for (const cd& p : l) o.emplace_back(p.real() * ps, (hgt - p.imag()) * ps);
    return o;
  };
  Shape shape;
  shape.outer = to_output(simple[0]);
  for (size_t i = 1; i < simple.size(); ++i) shape.holes.push_back(to_output(simple[i]));
  shape = normalize(std::move(shape));
  try {
    validate(shape);
  } catch (const InputError& e) {
    throw InputError(name + ": the traced shape is invalid after simplification: " + e.what());
  }
  fit_cage(shape, name, options, hgt, result.warnings);
  result.shape = std::move(shape);
  return result;
}

}  // namespace hsi
