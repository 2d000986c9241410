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
  // Where the two segments' lines meet (the midpoint of the overlap when collinear).
  const cd da = a1 - a0, db = b1 - b0;
  const double den = da.real() * db.imag() - da.imag() * db.real();
  if (den != 0) {
    const cd w = b0 - a0;
    const double s = (w.real() * db.imag() - w.imag() * db.real()) / den;
    r.point = a0 + std::clamp(s, 0.0, 1.0) * da;
  } else {
    r.point = 0.25 * (a0 + a1 + b0 + b1);
  }
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

void push_point(Polylines& p, size_t loop, cd z, int origin, double merge) {
  Loop& l = p.loops[loop];
  if (!l.empty() && (l.back() == z || std::abs(l.back() - z) <= merge)) return;
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

OverlapChecker::OverlapChecker(const Cage& cage, const CertificateSegments& breakpoints)
    : seg_(breakpoints), f_(make_cpu_mesh_evaluator(cage, seg_.points)) {}

VectorXcd OverlapChecker::image(const HarmonicMap& map) const {
  MapValues v;
  f_->evaluate(map, v);  // InputError for a map of another cage
  return std::move(v.f);
}

OverlapResult OverlapChecker::check(const HarmonicMap& map) const {
  const VectorXcd f = image(map);
  return check_points(std::span<const cd>(f.data(), static_cast<size_t>(f.size())));
}

OverlapResult OverlapChecker::check_points(std::span<const cd> image) const {
  if (image.size() != seg_.size())
    throw InputError("overlap check: " + std::to_string(image.size()) + " image points for " + std::to_string(seg_.size()) +
                     " breakpoints");
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
