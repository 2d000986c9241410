// Shape geometry, orientation and validation (math.md §1).
#include "hsi/domain.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <queue>
#include <sstream>

#include "cgal_geometry.h"

namespace hsi {

void write_file_atomic(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  // C stdio, for errno: a message says why the system refused (no such folder, permission, disk full).
  const auto why = [] { return std::string(std::strerror(errno)); };
  errno = 0;
  std::FILE* out = std::fopen(tmp.c_str(), "wb");
  if (!out) throw InputError(path.string() + ": cannot write: " + why());
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), out) == bytes.size() && std::fflush(out) == 0;
  const std::string reason = written ? "" : why();
  if (std::fclose(out) != 0 || !written) {
    const std::string r = reason.empty() ? why() : reason;
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InputError(path.string() + ": write failed: " + r);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string r = why();
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InputError(path.string() + ": cannot write: " + r);
  }
}

std::string loop_name(int loop) { return loop == 0 ? "outer loop" : "hole " + std::to_string(loop); }

double signed_area(const Loop& loop) {
  double a = 0;
  const size_t n = loop.size();
  for (size_t i = 0; i < n; ++i) {
    const cd p = loop[i], q = loop[(i + 1) % n];
    a += p.real() * q.imag() - q.real() * p.imag();
  }
  return 0.5 * a;
}

double perimeter(const Loop& loop) {
  double s = 0;
  for (size_t i = 0; i < loop.size(); ++i) s += std::abs(loop[(i + 1) % loop.size()] - loop[i]);
  return s;
}

double area(const Shape& shape) {
  double a = std::abs(signed_area(shape.outer));
  for (const Loop& h : shape.holes) a -= std::abs(signed_area(h));
  return a;
}

bool point_in_loop(const Loop& loop, cd p) {
  bool inside = false;
  const size_t n = loop.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const cd a = loop[i], b = loop[j];
    if ((a.imag() > p.imag()) != (b.imag() > p.imag())) {
      const double x = a.real() + (p.imag() - a.imag()) * (b.real() - a.real()) / (b.imag() - a.imag());
      if (p.real() < x) inside = !inside;
    }
  }
  return inside;
}

bool point_in_shape(const Shape& shape, cd p) {
  if (!point_in_loop(shape.outer, p)) return false;
  for (const Loop& h : shape.holes)
    if (point_in_loop(h, p)) return false;
  return true;
}

double segment_distance(cd p, cd a, cd b) {
  const cd ab = b - a;
  const double len2 = std::norm(ab);
  double t = len2 > 0 ? ((p - a) * std::conj(ab)).real() / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::abs(p - (a + t * ab));
}

double loop_distance(const Loop& loop, cd p) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < loop.size(); ++i) d = std::min(d, segment_distance(p, loop[i], loop[(i + 1) % loop.size()]));
  return d;
}

double boundary_distance(const Shape& shape, cd p) {
  double d = loop_distance(shape.outer, p);
  for (const Loop& h : shape.holes) d = std::min(d, loop_distance(h, p));
  return d;
}

namespace {
double cross(cd u, cd v) { return u.real() * v.imag() - u.imag() * v.real(); }
}  // namespace

double segment_segment_distance(cd a0, cd a1, cd b0, cd b1) {
  const double d1 = cross(a1 - a0, b0 - a0), d2 = cross(a1 - a0, b1 - a0);
  const double d3 = cross(b1 - b0, a0 - b0), d4 = cross(b1 - b0, a1 - b0);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 0.0;
  return std::min({segment_distance(a0, b0, b1), segment_distance(a1, b0, b1), segment_distance(b0, a0, a1),
                   segment_distance(b1, a0, a1)});
}

BoundingBox bounding_box(const Loop& loop) {
  const double inf = std::numeric_limits<double>::infinity();
  BoundingBox b{{inf, inf}, {-inf, -inf}};
  for (const cd& p : loop) {
    b.lo = {std::min(b.lo.real(), p.real()), std::min(b.lo.imag(), p.imag())};
    b.hi = {std::max(b.hi.real(), p.real()), std::max(b.hi.imag(), p.imag())};
  }
  return b;
}

BoundingBox bounding_box(const Shape& shape) { return bounding_box(shape.outer); }

Loop subdivide_edges(const Loop& loop, double max_edge) {
  if (!(max_edge > 0)) throw InputError("subdivide_edges: max_edge must be positive");
  Loop out;
  for (size_t i = 0; i < loop.size(); ++i) {
    const cd p = loop[i], q = loop[(i + 1) % loop.size()];
    const int parts = std::max(1, static_cast<int>(std::ceil(std::abs(q - p) / max_edge - 1e-9)));
    for (int k = 0; k < parts; ++k) out.push_back(p + (q - p) * (static_cast<double>(k) / parts));
  }
  return out;
}

Shape normalize(Shape shape) {
  if (signed_area(shape.outer) < 0) std::reverse(shape.outer.begin(), shape.outer.end());
  for (Loop& h : shape.holes)
    if (signed_area(h) > 0) std::reverse(h.begin(), h.end());
  return shape;
}

namespace {
std::string edge_name(int loop, int edge, int n) {
  std::ostringstream s;
  s << loop_name(loop) << " edge " << edge << " (vertex " << edge << " -> " << (edge + 1) % n << ")";
  return s.str();
}
std::string fmt_point(cd p) {
  std::ostringstream s;
  s.precision(10);
  s << "(" << p.real() << ", " << p.imag() << ")";
  return s.str();
}
}  // namespace

void validate(const Shape& shape) {
  const int loops = shape.loop_count();
  // Per-loop checks first: they make the later predicates meaningful.
  for (int l = 0; l < loops; ++l) {
    const Loop& loop = shape.loop(l);
    const int n = static_cast<int>(loop.size());
    if (n < 3)
      throw InputError(loop_name(l) + " has " + std::to_string(n) + " vertices; a loop needs at least 3");
    for (int i = 0; i < n; ++i) {
      const cd p = loop[static_cast<size_t>(i)];
      if (!std::isfinite(p.real()) || !std::isfinite(p.imag()))
        throw InputError(loop_name(l) + " vertex " + std::to_string(i) + " has a non-finite coordinate " +
                         fmt_point(p));
      if (std::abs(p.real()) > 1e12 || std::abs(p.imag()) > 1e12)
        throw InputError(loop_name(l) + " vertex " + std::to_string(i) + " has a coordinate beyond 1e12 " +
                         fmt_point(p) + "; rescale the shape");
    }
  }
  const double size = bounding_box(shape.outer).diagonal();
  for (int l = 0; l < loops; ++l) {
    const Loop& loop = shape.loop(l);
    const int n = static_cast<int>(loop.size());
    for (int i = 0; i < n; ++i) {
      const cd p = loop[static_cast<size_t>(i)], q = loop[static_cast<size_t>((i + 1) % n)];
      if (std::abs(q - p) <= 1e-12 * size)
        throw InputError(loop_name(l) + " has a zero-length " + edge_name(l, i, n) + ": vertices " +
                         std::to_string(i) + " and " + std::to_string((i + 1) % n) + " coincide at " + fmt_point(p) +
                         (i + 1 == n ? " (a loop closes by itself: do not repeat its first vertex at the end)" : ""));
    }
  }
  std::vector<const Loop*> all;
  for (int l = 0; l < loops; ++l) all.push_back(&shape.loop(l));
  const auto hits = detail::intersecting_edges(all, 16);
  if (!hits.empty()) {
    const auto& [a, b] = hits.front();
    const int na = static_cast<int>(all[static_cast<size_t>(a.loop)]->size());
    const int nb = static_cast<int>(all[static_cast<size_t>(b.loop)]->size());
    if (a.loop == b.loop)
      throw InputError(loop_name(a.loop) + " intersects itself: " + edge_name(a.loop, a.edge, na) + " meets " +
                       edge_name(b.loop, b.edge, nb));
    throw InputError(loop_name(b.loop) + " crosses the " + loop_name(a.loop) + ": " + edge_name(a.loop, a.edge, na) +
                     " meets " + edge_name(b.loop, b.edge, nb));
  }
  // Simple loops from here on; a (near) zero area is still degenerate.
  for (int l = 0; l < loops; ++l) {
    const double loop_size = bounding_box(shape.loop(l)).diagonal();
    if (std::abs(signed_area(shape.loop(l))) <= 1e-10 * loop_size * loop_size)
      throw InputError(loop_name(l) + " encloses (almost) no area: its vertices are (nearly) collinear");
  }
  // No crossings: one vertex decides containment of a whole loop.
  for (int h = 1; h < loops; ++h) {
    const cd p = shape.loop(h)[0];
    if (!point_in_loop(shape.outer, p))
      throw InputError(loop_name(h) + " lies outside the outer loop (its vertex 0 at " + fmt_point(p) + ")");
    for (int g = 1; g < loops; ++g)
      if (g != h && point_in_loop(shape.loop(g), p))
        throw InputError(loop_name(h) + " lies inside " + loop_name(g) + "; holes must be disjoint");
  }
  if (area(shape) <= 1e-10 * size * size) throw InputError("the shape has (almost) no area left after its holes");
}

Circle largest_inscribed_circle(const Loop& loop, double rel_tol) {
  // Polylabel: best-first search over square cells; a cell's potential is the
  // distance at its centre plus its half-diagonal.
  const BoundingBox bb = bounding_box(loop);
  const double w = bb.hi.real() - bb.lo.real(), h = bb.hi.imag() - bb.lo.imag();
  const double cell = std::min(w, h);
  const double tol = rel_tol * std::max(w, h);
  auto sdist = [&](cd p) { return (point_in_loop(loop, p) ? 1.0 : -1.0) * loop_distance(loop, p); };
  struct Cell {
    cd c;
    double half, d, potential;
    bool operator<(const Cell& o) const { return potential < o.potential; }
  };
  auto make = [&](cd c, double half) {
    const double d = sdist(c);
    return Cell{c, half, d, d + half * std::sqrt(2.0)};
  };
  std::priority_queue<Cell> queue;
  for (double x = bb.lo.real(); x < bb.hi.real(); x += cell)
    for (double y = bb.lo.imag(); y < bb.hi.imag(); y += cell) queue.push(make({x + cell / 2, y + cell / 2}, cell / 2));
  // Start from the centroid of the vertices (often inside) or the first cell.
  cd centroid = 0;
  for (const cd& p : loop) centroid += p;
  centroid /= static_cast<double>(loop.size());
  Cell best = make(centroid, 0);
  while (!queue.empty()) {
    const Cell c = queue.top();
    queue.pop();
    if (c.d > best.d) best = c;
    if (c.potential - best.d <= tol) continue;
    const double q = c.half / 2;
    for (cd o : {cd{-q, -q}, cd{q, -q}, cd{-q, q}, cd{q, q}}) queue.push(make(c.c + o, q));
  }
  return {best.c, std::max(best.d, 0.0)};
}

}  // namespace hsi
