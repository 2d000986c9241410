// Global overlap: self-crossings of the boundary's image (hsi/overlap.h).
#include "hsi/overlap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "cgal_geometry.h"

namespace hsi {
namespace {

// Image polylines with exact repeats of a point dropped (a zero-length segment would
// make its two neighbours "cross" at the repeated point); origin[l][i] is the input
// index of polyline vertex i of loop l.
struct Polylines {
  std::vector<Loop> loops;
  std::vector<std::vector<int>> origin;
};

// Where segments [a0, a1] and [b0, b1] cross: where their lines meet (the midpoint of
// the overlap when collinear).
cd crossing_point(cd a0, cd a1, cd b0, cd b1) {
  const cd da = a1 - a0, db = b1 - b0;
  const double den = da.real() * db.imag() - da.imag() * db.real();
  if (den != 0) {
    const cd w = b0 - a0;
    const double s = (w.real() * db.imag() - w.imag() * db.real()) / den;
    return a0 + std::clamp(s, 0.0, 1.0) * da;
  }
  return 0.25 * (a0 + a1 + b0 + b1);
}

// The reference search (check_points_reference): the polylines and a hierarchy over
// them made per call.
OverlapResult search(const Polylines& p, int points) {
  OverlapResult r;
  r.checked = true;
  r.points = points;
  std::vector<const Loop*> ptrs;
  for (const Loop& l : p.loops) {
    if (l.size() < 3) continue;  // a loop collapsed to fewer than 3 distinct image points has no segments to cross
    ptrs.push_back(&l);
  }
  if (ptrs.empty()) return r;
  std::vector<int> loop_index;
  for (size_t k = 0; k < p.loops.size(); ++k)
    if (p.loops[k].size() >= 3) loop_index.push_back(static_cast<int>(k));
  const auto found = detail::intersecting_edges(ptrs, std::numeric_limits<size_t>::max());
  r.crossings = static_cast<int>(std::min<size_t>(found.size(), static_cast<size_t>(std::numeric_limits<int>::max())));
  if (found.empty()) return r;
  const auto& [a, b] = found.front();
  const int la = loop_index[static_cast<size_t>(a.loop)], lb = loop_index[static_cast<size_t>(b.loop)];
  const Loop& A = p.loops[static_cast<size_t>(la)];
  const Loop& B = p.loops[static_cast<size_t>(lb)];
  const cd a0 = A[static_cast<size_t>(a.edge)], a1 = A[(static_cast<size_t>(a.edge) + 1) % A.size()];
  const cd b0 = B[static_cast<size_t>(b.edge)], b1 = B[(static_cast<size_t>(b.edge) + 1) % B.size()];
  r.point = crossing_point(a0, a1, b0, b1);
  r.loop_a = la;
  r.edge_a = p.origin[static_cast<size_t>(la)][static_cast<size_t>(a.edge)];
  r.loop_b = lb;
  r.edge_b = p.origin[static_cast<size_t>(lb)][static_cast<size_t>(b.edge)];
  return r;
}

// Image points closer than this fraction of the image's size to the last point kept
// on their loop are merged into it (overlap.h: the tolerance).
constexpr double kMergeFraction = 1e-9;

double merge_distance(std::span<const cd> image) {
  if (image.empty()) return 0;
  double x0 = image[0].real(), x1 = x0, y0 = image[0].imag(), y1 = y0;
  for (const cd& z : image) {
    x0 = std::min(x0, z.real());
    x1 = std::max(x1, z.real());
    y0 = std::min(y0, z.imag());
    y1 = std::max(y1, z.imag());
  }
  return kMergeFraction * std::hypot(x1 - x0, y1 - y0);
}

// Whether z is merged into `kept`, the last point kept on its loop (or a loop's last
// point into its first).
// |kept − z| is never below its larger coordinate difference (nor is its rounding: that
// difference is a double), so past `merge` there the distance is not computed: the same
// decision, without a hypot per point.
bool merged(cd kept, cd z, double merge) {
  const cd d = kept - z;
  if (std::max(std::abs(d.real()), std::abs(d.imag())) > merge) return false;
  return kept == z || std::abs(d) <= merge;
}

void push_point(Polylines& p, size_t loop, cd z, int origin, double merge) {
  Loop& l = p.loops[loop];
  if (!l.empty() && (l.back() == z || std::abs(l.back() - z) <= merge)) return;  // merged(), as it was written before

  l.push_back(z);
  p.origin[loop].push_back(origin);
}

void close_loop(Polylines& p, size_t loop, double merge) {
  Loop& l = p.loops[loop];
  while (l.size() > 1 && (l.back() == l.front() || std::abs(l.back() - l.front()) <= merge)) {
    l.pop_back();
    p.origin[loop].pop_back();
  }
}

// Whether every point is finite, and if so merge_distance(image) in `merge`: one pass.
bool finite_merge_distance(std::span<const cd> image, double& merge) {
  merge = 0;
  if (image.empty()) return true;
  double x0 = image[0].real(), x1 = x0, y0 = image[0].imag(), y1 = y0;
  for (const cd& z : image) {
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) return false;
    x0 = std::min(x0, z.real());
    x1 = std::max(x1, z.real());
    y0 = std::min(y0, z.imag());
    y1 = std::max(y1, z.imag());
  }
  merge = kMergeFraction * std::hypot(x1 - x0, y1 - y0);
  return true;
}

}  // namespace

// The loops' slots, fixed per checker: slot s holds image point `point[s]` (the points
// of loop 0 in their order, then loop 1's, ...), which lies on loop `loop[s]` and is
// reported as its edge (or polyline vertex) `origin[s]`.
struct detail::OverlapLayout {
  std::vector<int> loop_begin;  // loop l's slots: [loop_begin[l], loop_begin[l + 1])
  std::vector<int> point;       // empty: slot s is image point s
  std::vector<int> loop, origin;
  LoopHierarchy tree;

  OverlapLayout(std::span<const int> loop_of, std::span<const int> origin_of)
      : OverlapLayout(loop_of, origin_of, slots_per_loop(loop_of)) {}

 private:
  OverlapLayout(std::span<const int> loop_of, std::span<const int> origin_of, const std::vector<int>& slots)
      : tree(slots) {
    loop_begin.push_back(0);
    for (int n : slots) loop_begin.push_back(loop_begin.back() + n);
    std::vector<int> cursor(loop_begin.begin(), loop_begin.end() - 1);
    point.resize(loop_of.size());
    loop.resize(loop_of.size());
    origin.resize(loop_of.size());
    bool identity = true;
    for (size_t i = 0; i < loop_of.size(); ++i) {
      const int s = cursor[static_cast<size_t>(loop_of[i])]++;
      point[static_cast<size_t>(s)] = static_cast<int>(i);
      loop[static_cast<size_t>(s)] = loop_of[i];
      origin[static_cast<size_t>(s)] = origin_of[i];
      identity = identity && s == static_cast<int>(i);
    }
    if (identity) point.clear();
  }

  static std::vector<int> slots_per_loop(std::span<const int> loop_of) {
    std::vector<int> n;
    for (int l : loop_of) {
      if (l < 0) throw InputError("overlap check: a breakpoint on loop " + std::to_string(l));
      if (static_cast<size_t>(l) >= n.size()) n.resize(static_cast<size_t>(l) + 1, 0);
      ++n[static_cast<size_t>(l)];
    }
    return n;
  }
};

struct detail::OverlapScratch {
  std::vector<cd> z;      // the image in slot order (when that is not the image's own)
  std::vector<int> next;  // per slot: the slot its polyline segment ends at; −1: merged away
  std::vector<int> kept;  // one loop's kept slots
  LoopHierarchy::Workspace tree;
};

namespace {

// The polylines of check_points_reference, as slots: the same points merged (push_point,
// close_loop), each kept slot's segment ending at the next kept slot of its loop, loops
// of fewer than 3 kept points left out; then the hierarchy decides every pair exactly as
// intersecting_edges does, and the first pair in slot order is (loop, segment) order.
OverlapResult find_crossings(const detail::OverlapLayout& L, std::span<const cd> image, detail::OverlapScratch& s) {
  OverlapResult r;
  double merge = 0;
  if (!finite_merge_distance(image, merge)) return r;  // a map that is not finite on the boundary: nothing to decide
  r.checked = true;
  r.points = static_cast<int>(image.size());
  std::span<const cd> z = image;
  if (!L.point.empty()) {
    s.z.resize(image.size());
    for (size_t k = 0; k < s.z.size(); ++k) s.z[k] = image[static_cast<size_t>(L.point[k])];
    z = s.z;
  }
  s.next.assign(image.size(), -1);
  for (size_t l = 0; l + 1 < L.loop_begin.size(); ++l) {
    s.kept.clear();
    for (int k = L.loop_begin[l]; k < L.loop_begin[l + 1]; ++k)
      if (s.kept.empty() || !merged(z[static_cast<size_t>(s.kept.back())], z[static_cast<size_t>(k)], merge)) s.kept.push_back(k);
    while (s.kept.size() > 1 && merged(z[static_cast<size_t>(s.kept.back())], z[static_cast<size_t>(s.kept.front())], merge))
      s.kept.pop_back();
    if (s.kept.size() < 3) continue;  // no segments to cross
    for (size_t k = 0; k + 1 < s.kept.size(); ++k) s.next[static_cast<size_t>(s.kept[k])] = s.kept[k + 1];
    s.next[static_cast<size_t>(s.kept.back())] = s.kept.front();
  }
  const detail::LoopHierarchy::Crossings c = L.tree.search(z, s.next, s.tree);
  if (c.count == 0) return r;
  r.crossings = static_cast<int>(std::min<long>(c.count, std::numeric_limits<int>::max()));
  const size_t a = static_cast<size_t>(c.a), b = static_cast<size_t>(c.b);
  r.point = crossing_point(z[a], z[static_cast<size_t>(s.next[a])], z[b], z[static_cast<size_t>(s.next[b])]);
  r.loop_a = L.loop[a];
  r.edge_a = L.origin[a];
  r.loop_b = L.loop[b];
  r.edge_b = L.origin[b];
  return r;
}

std::string point_text(cd z) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g)", z.real(), z.imag());
  return buf;
}

}  // namespace

std::string describe(const OverlapResult& r) {
  if (!r.checked) return "not checked";
  if (!r.overlaps())
    return "no self-crossing of the boundary's image (sampled at " + std::to_string(r.points) + " boundary breakpoints)";
  return "overlaps itself: the image of the " + loop_name(r.loop_a) + " edge " + std::to_string(r.edge_a) + " crosses the " +
         loop_name(r.loop_b) + " edge " + std::to_string(r.edge_b) + " at " + point_text(r.point) + " (" +
         std::to_string(r.crossings) + (r.crossings == 1 ? " crossing" : " crossings") + " at " + std::to_string(r.points) +
         " boundary breakpoints)";
}

OverlapChecker::Workspace::Workspace() : scratch_(std::make_unique<detail::OverlapScratch>()) {}
OverlapChecker::Workspace::~Workspace() = default;
OverlapChecker::Workspace::Workspace(Workspace&&) noexcept = default;
OverlapChecker::Workspace& OverlapChecker::Workspace::operator=(Workspace&&) noexcept = default;

OverlapChecker::OverlapChecker(const Cage& cage, const CertificateSegments& breakpoints)
    : seg_(breakpoints),
      f_(make_cpu_mesh_evaluator(cage, seg_.points)),
      layout_(std::make_shared<const detail::OverlapLayout>(seg_.loop, seg_.edge)) {}

VectorXcd OverlapChecker::image(const HarmonicMap& map) const {
  MapValues v;
  image(map, v);
  return std::move(v.f);
}

void OverlapChecker::image(const HarmonicMap& map, MapValues& out) const {
  f_->evaluate(map, out);  // InputError for a map of another cage
}

OverlapResult OverlapChecker::check(const HarmonicMap& map) const {
  const VectorXcd f = image(map);
  return check_points(std::span<const cd>(f.data(), static_cast<size_t>(f.size())));
}

namespace {
void check_size(std::span<const cd> image, size_t breakpoints) {
  if (image.size() != breakpoints)
    throw InputError("overlap check: " + std::to_string(image.size()) + " image points for " + std::to_string(breakpoints) +
                     " breakpoints");
}
}  // namespace

OverlapResult OverlapChecker::check_points(std::span<const cd> image, Workspace& workspace) const {
  check_size(image, seg_.size());
  return find_crossings(*layout_, image, workspace.scratch());
}

OverlapResult OverlapChecker::check_points(std::span<const cd> image) const {
  Workspace w;
  return check_points(image, w);
}

OverlapResult OverlapChecker::check_points_reference(std::span<const cd> image) const {
  check_size(image, seg_.size());
  int loops = 0;
  for (int l : seg_.loop) loops = std::max(loops, l + 1);
  Polylines p;
  p.loops.resize(static_cast<size_t>(loops));
  p.origin.resize(static_cast<size_t>(loops));
  const double merge = merge_distance(image);
  for (size_t i = 0; i < image.size(); ++i) {
    if (!std::isfinite(image[i].real()) || !std::isfinite(image[i].imag())) {
      OverlapResult r;  // a map that is not finite on the boundary: nothing to decide
      return r;
    }
    // Segment i starts at breakpoint i and lies on polygon edge seg_.edge[i].
    push_point(p, static_cast<size_t>(seg_.loop[i]), image[i], seg_.edge[i], merge);
  }
  for (size_t l = 0; l < p.loops.size(); ++l) close_loop(p, l, merge);
  return search(p, static_cast<int>(image.size()));
}

OverlapResult polyline_overlap(const std::vector<Loop>& loops) {
  std::vector<cd> all;
  std::vector<int> loop_of, vertex;
  for (size_t l = 0; l < loops.size(); ++l)
    for (size_t i = 0; i < loops[l].size(); ++i) {
      all.push_back(loops[l][i]);
      loop_of.push_back(static_cast<int>(l));
      vertex.push_back(static_cast<int>(i));
    }
  const detail::OverlapLayout layout(loop_of, vertex);
  detail::OverlapScratch scratch;
  return find_crossings(layout, all, scratch);
}

OverlapResult polyline_overlap_reference(const std::vector<Loop>& loops) {
  Polylines p;
  p.loops.resize(loops.size());
  p.origin.resize(loops.size());
  int points = 0;
  std::vector<cd> all;
  for (const Loop& l : loops) all.insert(all.end(), l.begin(), l.end());
  const double merge = merge_distance(all);
  for (size_t l = 0; l < loops.size(); ++l) {
    for (size_t i = 0; i < loops[l].size(); ++i) push_point(p, l, loops[l][i], static_cast<int>(i), merge);
    close_loop(p, l, merge);
    points += static_cast<int>(loops[l].size());
  }
  return search(p, points);
}

}  // namespace hsi
