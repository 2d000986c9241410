// Automatic cage construction: Clipper offsets, then constrained Visvalingam
// decimation down to tens of vertices per loop (math.md §1).
#include "hsi/cage.h"

#include <clipper.hpp>

#include <algorithm>
#include <cmath>
#include <queue>
#include <sstream>

#include "cgal_geometry.h"

namespace hsi {
namespace {

double cross(cd u, cd v) { return u.real() * v.imag() - u.imag() * v.real(); }

// Offsets a simple loop by delta (> 0 grows it, < 0 shrinks it) and returns the
// largest resulting polygon (a shrunk dumbbell may split; a grown C may close).
Loop offset_loop(const Loop& loop, double delta) {
  const BoundingBox bb = bounding_box(loop);
  const double extent = std::max(bb.diagonal() + 2 * std::abs(delta), 1e-300);
  const double scale = 1e9 / extent;  // integer coordinates of about 30 bits
  const cd origin = (bb.lo + bb.hi) / 2.0;
  ClipperLib::Path path;
  for (const cd& p : loop) {
    const cd q = (p - origin) * scale;
    path.emplace_back(static_cast<ClipperLib::cInt>(std::llround(q.real())),
                      static_cast<ClipperLib::cInt>(std::llround(q.imag())));
  }
  ClipperLib::ClipperOffset co;
  co.ArcTolerance = std::abs(delta) * scale * 0.01;
  co.AddPath(path, ClipperLib::jtRound, ClipperLib::etClosedPolygon);
  ClipperLib::Paths out;
  co.Execute(out, delta * scale);
  double best_area = 0;
  Loop best;
  for (const auto& p : out) {
    const double a = std::abs(ClipperLib::Area(p));
    if (a <= best_area) continue;
    best_area = a;
    best.clear();
    for (const auto& ip : p) best.push_back(origin + cd(static_cast<double>(ip.X), static_cast<double>(ip.Y)) / scale);
  }
  return best;
}

// Removes vertices of `cage` (smallest triangle area first) while the loop stays
// simple, every new edge stays at least min_dist from `boundary`, and (for the
// outer cage) the removed triangle does not swallow the shape.
Loop decimate(Loop cage, const Loop& boundary, double min_dist, int target, bool outer) {
  // Near-duplicate vertices would give nearly dependent basis columns: merge them first.
  Loop merged;
  for (const cd& p : cage)
    if (merged.empty() || std::abs(p - merged.back()) > 1e-4 * min_dist) merged.push_back(p);
  while (merged.size() > 3 && std::abs(merged.front() - merged.back()) <= 1e-4 * min_dist) merged.pop_back();
  cage = std::move(merged);
  const int n = static_cast<int>(cage.size());
  if (n <= target) return cage;
  // Cap edge lengths so that vertices spread along long straight sides instead of
  // gathering at rounded corners (the basis can then bend a long stroke).
  const double max_edge = 2.0 * perimeter(cage) / target;
  std::vector<int> prev(static_cast<size_t>(n)), next(static_cast<size_t>(n)), version(static_cast<size_t>(n), 0);
  std::vector<char> alive(static_cast<size_t>(n), 1);
  for (int i = 0; i < n; ++i) {
    prev[static_cast<size_t>(i)] = (i + n - 1) % n;
    next[static_cast<size_t>(i)] = (i + 1) % n;
  }
  auto P = [&](int i) { return cage[static_cast<size_t>(i)]; };
  auto tri_area = [&](int i) {
    return std::abs(cross(P(prev[static_cast<size_t>(i)]) - P(i), P(next[static_cast<size_t>(i)]) - P(i))) / 2;
  };
  struct Item {
    double area;
    int v, version;
    bool operator<(const Item& o) const { return area > o.area || (area == o.area && v > o.v); }  // min-heap
  };
  std::priority_queue<Item> heap;
  for (int i = 0; i < n; ++i) heap.push({tri_area(i), i, 0});

  // Strictly inside: a vertex on the new edge is caught by the edge test below, and
  // collinear vertices along a straight stroke must not block each other's removal.
  auto in_triangle = [](cd p, cd a, cd b, cd c) {
    const double d1 = cross(b - a, p - a), d2 = cross(c - b, p - b), d3 = cross(a - c, p - c);
    return (d1 > 0 && d2 > 0 && d3 > 0) || (d1 < 0 && d2 < 0 && d3 < 0);
  };
  auto feasible = [&](int v) {
    const int a = prev[static_cast<size_t>(v)], b = next[static_cast<size_t>(v)];
    const cd pa = P(a), pb = P(b), pv = P(v);
    if (std::abs(pb - pa) > max_edge) return false;
    const int nb = static_cast<int>(boundary.size());
    for (int i = 0; i < nb; ++i)
      if (segment_segment_distance(pa, pb, boundary[static_cast<size_t>(i)], boundary[static_cast<size_t>((i + 1) % nb)]) <
          min_dist)
        return false;
    if (outer && in_triangle(boundary[0], pa, pv, pb)) return false;
    for (int i = next[static_cast<size_t>(b)]; i != a; i = next[static_cast<size_t>(i)]) {
      const int j = next[static_cast<size_t>(i)];
      if (in_triangle(P(i), pa, pv, pb)) return false;
      if (j != a && segment_segment_distance(pa, pb, P(i), P(j)) == 0.0) return false;
    }
    // The edges next to the new one may not fold back onto it.
    if (segment_segment_distance(pa, pb, P(prev[static_cast<size_t>(a)]), pa) == 0.0 &&
        cross(pb - pa, P(prev[static_cast<size_t>(a)]) - pa) == 0.0)
      return false;
    return true;
  };

  int count = n;
  while (count > target && !heap.empty()) {
    const Item it = heap.top();
    heap.pop();
    if (!alive[static_cast<size_t>(it.v)] || it.version != version[static_cast<size_t>(it.v)]) continue;
    if (!feasible(it.v)) continue;  // reconsidered when a neighbour changes
    const int a = prev[static_cast<size_t>(it.v)], b = next[static_cast<size_t>(it.v)];
    alive[static_cast<size_t>(it.v)] = 0;
    next[static_cast<size_t>(a)] = b;
    prev[static_cast<size_t>(b)] = a;
    --count;
    for (int u : {a, b}) heap.push({tri_area(u), u, ++version[static_cast<size_t>(u)]});
  }
  Loop out;
  int start = 0;
  while (!alive[static_cast<size_t>(start)]) ++start;
  int i = start;
  do {
    out.push_back(P(i));
    i = next[static_cast<size_t>(i)];
  } while (i != start);
  return out;
}

std::string fmt_point(cd p) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << p.real() << ", " << p.imag() << ")";
  return s.str();
}

}  // namespace

Cage build_cage(const Shape& shape, const CageOptions& o) {
  if (!(o.clearance > 0) || !(o.min_clearance > 0 && o.min_clearance < 1) || !(o.hole_clearance > 0 && o.hole_clearance < 1))
    throw InputError("cage options: clearance must be > 0, min_clearance and hole_clearance in (0, 1)");
  if (o.max_vertices_per_loop < 4) throw InputError("cage options: max_vertices_per_loop must be at least 4");
  const double diag = bounding_box(shape).diagonal();
  const double d = o.clearance * diag;
  const double outer_perimeter = perimeter(shape.outer);
  Cage cage;
  for (int k = 0; k < shape.loop_count(); ++k) {
    const Loop& loop = shape.loop(k);
    double dk = d;
    int target = o.max_vertices_per_loop;
    if (k > 0) {
      const Circle c = largest_inscribed_circle(loop);
      cage.hole_points.push_back(c.center);
      dk = std::min(d, o.hole_clearance * c.radius);
      const int by_length = static_cast<int>(std::lround(o.max_vertices_per_loop * perimeter(loop) / outer_perimeter));
      target = std::clamp(by_length, std::min(12, o.max_vertices_per_loop), o.max_vertices_per_loop);
    }
    Loop off = offset_loop(loop, k == 0 ? dk : -dk);
    if (off.size() < 3) throw InputError("could not offset the " + loop_name(k) + " to build its cage");
    const bool ccw = signed_area(off) > 0;
    if (ccw != (k == 0)) std::reverse(off.begin(), off.end());
    cage.loops.push_back(decimate(std::move(off), loop, o.min_clearance * dk, target, k == 0));
  }
  check_cage(shape, cage);
  return cage;
}

double cage_clearance(const Shape& shape, const Cage& cage) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < shape.loop_count(); ++k) {
    const Loop& s = shape.loop(k);
    for (const Loop& c : cage.loops)
      for (size_t i = 0; i < s.size(); ++i)
        for (size_t j = 0; j < c.size(); ++j)
          best = std::min(best, segment_segment_distance(s[i], s[(i + 1) % s.size()], c[j], c[(j + 1) % c.size()]));
  }
  for (const cd& rho : cage.hole_points) best = std::min(best, boundary_distance(shape, rho));
  return best;
}

double sufficient_hole_radius(double size, const CageOptions& o, double min_distance) {
  return min_distance * size / (o.hole_clearance * o.min_clearance);
}

void check_cage(const Shape& shape, const Cage& cage, double min_distance) {
  if (static_cast<int>(cage.loops.size()) != shape.loop_count())
    throw InputError("the cage has " + std::to_string(cage.loops.size()) + " loops; the shape has " +
                     std::to_string(shape.loop_count()) + " (one cage loop per boundary loop)");
  if (cage.hole_count() != static_cast<int>(shape.holes.size()))
    throw InputError("the cage has " + std::to_string(cage.hole_count()) + " hole points; the shape has " +
                     std::to_string(shape.holes.size()) + " holes");
  for (int k = 0; k < shape.loop_count(); ++k) {
    const Loop& c = cage.loops[static_cast<size_t>(k)];
    if (c.size() < 3) throw InputError("cage loop of the " + loop_name(k) + " has fewer than 3 vertices");
    for (size_t i = 0; i < c.size(); ++i)
      if (!std::isfinite(c[i].real()) || !std::isfinite(c[i].imag()))
        throw InputError("cage loop of the " + loop_name(k) + " vertex " + std::to_string(i) + " is not finite");
  }
  for (size_t h = 0; h < cage.hole_points.size(); ++h)
    if (!std::isfinite(cage.hole_points[h].real()) || !std::isfinite(cage.hole_points[h].imag()))
      throw InputError("hole point " + std::to_string(h + 1) + " is not finite");
  // Cage loops first, then the shape's loops: exact intersection search over all.
  std::vector<const Loop*> all;
  for (const Loop& c : cage.loops) all.push_back(&c);
  for (int k = 0; k < shape.loop_count(); ++k) all.push_back(&shape.loop(k));
  const int L = shape.loop_count();
  for (const auto& [a, b] : detail::intersecting_edges(all, 64)) {
    if (a.loop >= L) continue;  // shape against shape: validate() covers it
    const std::string ca = "cage loop of the " + loop_name(a.loop);
    if (b.loop < L) {
      if (a.loop == b.loop)
        throw InputError(ca + " is not simple: its edge " + std::to_string(a.edge) + " meets its edge " + std::to_string(b.edge));
      throw InputError(ca + " crosses the cage loop of the " + loop_name(b.loop));
    }
    throw InputError(ca + " touches the shape: cage edge " + std::to_string(a.edge) + " meets the " + loop_name(b.loop - L) +
                     " edge " + std::to_string(b.edge));
  }
  if (!point_in_loop(cage.loops[0], shape.outer[0]))
    throw InputError("the cage's outer loop does not enclose the shape");
  for (int k = 1; k < L; ++k) {
    const Loop& hole = shape.loop(k);
    if (!point_in_loop(hole, cage.loops[static_cast<size_t>(k)][0]))
      throw InputError("the cage loop for " + loop_name(k) + " is not inside that hole");
    const cd rho = cage.hole_points[static_cast<size_t>(k - 1)];
    if (!point_in_loop(hole, rho))
      throw InputError("hole point " + std::to_string(k) + " lies outside " + loop_name(k));
    if (loop_distance(cage.loops[static_cast<size_t>(k)], rho) < 1e-9 * bounding_box(hole).diagonal())
      throw InputError("hole point " + std::to_string(k) + " lies on the cage");
  }
  const double diag = bounding_box(shape).diagonal();
  const double clearance = cage_clearance(shape, cage);
  if (clearance < min_distance * diag) {
    // Name the closest pair (a shape loop and the cage loop or hole point near it) and what to do.
    double best = std::numeric_limits<double>::infinity();
    int shape_loop = 0, cage_loop = 0;
    bool hole_point = false;
    for (int k = 0; k < L; ++k) {
      const Loop& sl = shape.loop(k);
      for (int c = 0; c < L; ++c) {
        const Loop& cl = cage.loops[static_cast<size_t>(c)];
        for (size_t i = 0; i < sl.size(); ++i)
          for (size_t j = 0; j < cl.size(); ++j) {
            const double d = segment_segment_distance(sl[i], sl[(i + 1) % sl.size()], cl[j], cl[(j + 1) % cl.size()]);
            if (d < best) best = d, shape_loop = k, cage_loop = c, hole_point = false;
          }
      }
      for (int h = 0; h < cage.hole_count(); ++h) {
        const double d = loop_distance(sl, cage.hole_points[static_cast<size_t>(h)]);
        if (d < best) best = d, shape_loop = k, cage_loop = h + 1, hole_point = true;
      }
    }
    std::ostringstream m;
    m.precision(4);
    if (hole_point) m << "hole point " << cage_loop;
    else m << "the cage loop of the " << loop_name(cage_loop);
    m << " comes within " << clearance << " of the shape's " << loop_name(shape_loop) << "; at least " << min_distance * diag << " ("
      << min_distance << " of the shape's size) is needed so that boundary samples stay away from the basis singularities";
    if (cage_loop > 0) {
      const Circle c = largest_inscribed_circle(shape.loop(cage_loop));
      m << "; " << loop_name(cage_loop) << " (around " << fmt_point(c.center) << ") is " << 2 * c.radius
        << " across at its widest, too narrow for a cage at this distance: widen or remove that hole (hsi import-png "
           "fills such holes), or give a user cage that fits";
    } else {
      m << "; give the cage more room (\"cage\": {\"clearance\": larger}) or a user cage that fits";
    }
    throw InputError(m.str());
  }
}

}  // namespace hsi
